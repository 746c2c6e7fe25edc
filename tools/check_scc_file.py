#!/usr/bin/env python3
"""Checks an SCC raw-data file written by lidarsim's SCC export with netCDF4-python.

Usage: python3 tools/check_scc_file.py OUT.nc

Asserts the dimensions, every variable with its type and dimensions (the layout of
atmospheric_lidar's save_as_SCC_netcdf, see src/output/scc/ and docs/scc.md) and the
global attributes; a calibration measurement's Pol_Calib_Range_Min/Max. Exits non-zero on the first mismatch.
"""
import re
import sys

import netCDF4
import numpy as np

CH = ("channels",)
TS = ("time", "nb_of_time_scales")
I, D = np.dtype("int32"), np.dtype("float64")
VARIABLES = {
    "channel_ID": (CH, I),
    "Laser_Repetition_Rate": (CH, I),
    "Emitted_Wavelength": (CH, D),
    "Detected_Wavelength": (CH, D),
    "Raw_Data_Range_Resolution": (CH, D),
    "Background_Mode": (CH, I),
    "Background_Low": (CH, D),
    "Background_High": (CH, D),
    "Dead_Time_Corr_Type": (CH, I),
    "Dead_Time": (CH, D),
    "Acquisition_Mode": (CH, I),
    "Trigger_Delay": (CH, D),
    "LR_Input": (CH, I),
    "DAQ_Range": (CH, D),
    "First_Signal_Rangebin": (CH, I),
    "id_timescale": (CH, I),
    "Laser_Pointing_Angle": (("scan_angles",), D),
    "Molecular_Calc": ((), I),
    "Laser_Pointing_Angle_of_Profiles": (TS, I),
    "Raw_Data_Start_Time": (TS, I),
    "Raw_Data_Stop_Time": (TS, I),
    "Laser_Shots": (("time", "channels"), I),
    "Raw_Lidar_Data": (("time", "channels", "points"), D),
    "Pressure_at_Lidar_Station": ((), D),
    "Temperature_at_Lidar_Station": ((), D),
}
# a calibration measurement (export-scc-calibration) has these besides, both or neither
POL_CALIB = {"Pol_Calib_Range_Min": (CH, D), "Pol_Calib_Range_Max": (CH, D)}
ATTRIBUTES = {
    "Measurement_ID": r"\d{8}[0-9A-Za-z]{2}\d{2}",
    "RawData_Start_Date": r"\d{8}",
    "RawData_Start_Time_UT": r"\d{6}",
    "RawData_Stop_Time_UT": r"\d{6}",
}


def main(path):
    checks = 0
    with netCDF4.Dataset(path) as ds:
        dims = ds.dimensions
        for name in ("points", "channels", "time", "nb_of_time_scales", "scan_angles"):
            assert name in dims, f"dimension {name} missing"
            checks += 1
        assert dims["time"].isunlimited(), "time is not unlimited"
        assert len(dims["nb_of_time_scales"]) == 1 and len(dims["scan_angles"]) == 1
        for name, (vdims, dtype) in VARIABLES.items():
            assert name in ds.variables, f"variable {name} missing"
            v = ds.variables[name]
            assert v.dimensions == vdims, f"{name}: dims {v.dimensions}, want {vdims}"
            assert v.dtype == dtype, f"{name}: type {v.dtype}, want {dtype}"
            checks += 1
        calibration = [n in ds.variables for n in POL_CALIB]
        assert calibration[0] == calibration[1], "Pol_Calib_Range_Min/Max: one alone"
        if calibration[0]:
            for name, (vdims, dtype) in POL_CALIB.items():
                v = ds.variables[name]
                assert v.dimensions == vdims and v.dtype == dtype, f"{name}: {v.dimensions}"
            lo = ds.variables["Pol_Calib_Range_Min"][:]
            hi = ds.variables["Pol_Calib_Range_Max"][:]
            assert (lo < hi).all(), "Pol_Calib_Range_Min not below Pol_Calib_Range_Max"
            checks += 2
        allowed = set(VARIABLES) | (set(POL_CALIB) if calibration[0] else set())
        extra = set(ds.variables) - allowed
        assert not extra, f"unexpected variables {sorted(extra)}"
        for name, pattern in ATTRIBUTES.items():
            value = ds.getncattr(name)
            assert re.fullmatch(pattern, value), f"{name} = {value!r}"
            checks += 1
        shots = ds.variables["Laser_Shots"][:]
        assert (shots > 0).all(), "Laser_Shots not positive"
        start = ds.variables["Raw_Data_Start_Time"][:, 0]
        stop = ds.variables["Raw_Data_Stop_Time"][:, 0]
        assert start[0] == 0 and (stop > start).all(), "start/stop times"
        data = ds.variables["Raw_Lidar_Data"][:]
        # photon counts (Acquisition_Mode 1) are whole; analog signals (0) are mV per shot
        counting = ds.variables["Acquisition_Mode"][:] == 1
        pc = data[:, counting, :]
        assert (data >= 0).all() and np.all(pc == np.round(pc)), "counts"
        checks += 3
        # the pre-trigger bins: First_Signal_Rangebin below the bins, Background_Low/High
        # (m, range) before its start when the window is in the pre-trigger bins
        first = ds.variables["First_Signal_Rangebin"][:]
        assert ((first >= 0) & (first < len(dims["points"]))).all(), "First_Signal_Rangebin"
        checks += 1
        # station coordinates: both or neither, numbers in range
        has = [n in ds.ncattrs() for n in ("Latitude_degrees_north", "Longitude_degrees_east")]
        assert has[0] == has[1], "Latitude_degrees_north/Longitude_degrees_east: one alone"
        if has[0]:
            assert -90 <= float(ds.getncattr("Latitude_degrees_north")) <= 90, "latitude"
            assert -180 <= float(ds.getncattr("Longitude_degrees_east")) <= 180, "longitude"
        assert "Altitude_meter_asl" in ds.ncattrs(), "Altitude_meter_asl missing"
        checks += 2
    print(f"{checks} passed, 0 failed")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
