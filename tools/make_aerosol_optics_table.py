#!/usr/bin/env python3
"""Writes configs/fields/aerosol_optics_like_ifs.nc: a small MADE-UP aerosol optics table
in the layout of ECMWF's `aerosol_ifs_rrtm_*.nc` files distributed with ecRad
(netCDF-3 classic), holding the monochromatic variables lidarsim reads
(src/atmosphere/aerosol_species.rs, docs/model.md section 4l).

The layout follows ECMWF's own files (checked against aerosol_ifs_rrtm_49R1.nc's header
and ecRad's radiation/radiation_aerosol_optics_data.F90, which reads them):

  dimensions   hydrophilic (10), hydrophobic (14), relative_humidity (12),
               wavelength_mono, code_str (2)
  wavelength_mono(wavelength_mono)                         units "m"
  relative_humidity1(relative_humidity)                    lower RH bin bounds, units "1"
  relative_humidity2(relative_humidity)                    upper RH bin bounds, units "1"
  code_hydrophilic(hydrophilic, code_str), code_hydrophobic(hydrophobic, code_str)
  mass_ext_mono_hydrophilic(hydrophilic, relative_humidity, wavelength_mono)  m2 kg-1
  lidar_ratio_mono_hydrophilic(hydrophilic, relative_humidity, wavelength_mono) sr
  mass_ext_mono_hydrophobic(hydrophobic, wavelength_mono)                      m2 kg-1
  lidar_ratio_mono_hydrophobic(hydrophobic, wavelength_mono)  (units "1" in ECMWF's
                                                               file, kept so here)

all data float32 as in ECMWF's files. The type counts, codes and the RH bins' bounds are
the real files' structure (0, 0.1, ..., 0.8, 0.85, 0.9, 0.95 to 1); the wavelengths are
four of the real file's twenty (355, 532, 865, 1064 nm). The NUMBERS are made up (smooth
functions below), not ECMWF's: they only let the reader be tested.

  mass extinction, hydrophilic type t (1-based), RH bin mid h = (lower + upper)/2,
    wavelength ratio x = wavelength / 532 nm:
      k = (200 + 50 t) * (1 - 0.9 h)^-0.5 * x^-(0.2 + 0.1 t)          m2/kg
  lidar ratio, hydrophilic:  S = 20 + 3 t + 10 h + 5 x                  sr
  mass extinction, hydrophobic type t:  k = (100 + 40 t) * x^-(0.1 + 0.05 t)
  lidar ratio, hydrophobic:  S = 30 + 2 t + 4 x

tests/aerosol_optics_table.rs recomputes these formulas.

    /tmp/venv/bin/python tools/make_aerosol_optics_table.py [OUT.nc]
"""

import sys
from pathlib import Path

import numpy as np
import netCDF4

OUT = (
    Path(sys.argv[1])
    if len(sys.argv) > 1
    else Path(__file__).resolve().parents[1] / "configs" / "fields" / "aerosol_optics_like_ifs.nc"
)
WAVELENGTH_M = np.array([355e-9, 532e-9, 865e-9, 1064e-9])
RH_LOWER = np.array([0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.85, 0.9, 0.95])
RH_UPPER = np.append(RH_LOWER[1:], 1.0)
# the codes of ECMWF's 49R1 files' types, in their order
CODES_PHILIC = ["SS", "SS", "SS", "OM", "SU", "OB", "OA", "AM", "NI", "NI"]
CODES_PHOBIC = ["DD"] * 9 + ["OM", "BC", "BC", "BC", "SU"]


def philic(t, h, x):
    """Made-up (mass extinction m2/kg, lidar ratio sr) of hydrophilic type t at RH mid h."""
    k = (200.0 + 50.0 * t) * (1.0 - 0.9 * h) ** -0.5 * x ** -(0.2 + 0.1 * t)
    return k, 20.0 + 3.0 * t + 10.0 * h + 5.0 * x


def phobic(t, x):
    """Made-up (mass extinction m2/kg, lidar ratio sr) of hydrophobic type t."""
    return (100.0 + 40.0 * t) * x ** -(0.1 + 0.05 * t), 30.0 + 2.0 * t + 4.0 * x


def chars(codes):
    return np.array([list(c) for c in codes], dtype="S1")


def main():
    OUT.parent.mkdir(parents=True, exist_ok=True)
    d = netCDF4.Dataset(OUT, "w", format="NETCDF3_CLASSIC")
    d.createDimension("hydrophilic", len(CODES_PHILIC))
    d.createDimension("hydrophobic", len(CODES_PHOBIC))
    d.createDimension("relative_humidity", len(RH_LOWER))
    d.createDimension("wavelength_mono", len(WAVELENGTH_M))
    d.createDimension("code_str", 2)
    d.product_version = "made-up"
    d.comment = (
        "MADE-UP numbers in the layout of ECMWF's aerosol_ifs_rrtm_*.nc (ecRad), written by "
        "lidarsim's tools/make_aerosol_optics_table.py to test its reader. Not ECMWF data: "
        "use ECMWF's own file for simulations."
    )
    d.description_hydrophilic = "\n".join(f"{i + 1}: made-up {c}" for i, c in enumerate(CODES_PHILIC))
    d.description_hydrophobic = "\n".join(f"{i + 1}: made-up {c}" for i, c in enumerate(CODES_PHOBIC))

    v = d.createVariable("wavelength_mono", "f4", ("wavelength_mono",))
    v.units, v.long_name = "m", "Wavelength of monochromatic data"
    v[:] = WAVELENGTH_M
    v = d.createVariable("relative_humidity1", "f4", ("relative_humidity",))
    v.units, v.long_name = "1", "Lower bounds of relative humidity bins"
    v[:] = RH_LOWER
    v = d.createVariable("relative_humidity2", "f4", ("relative_humidity",))
    v.units, v.long_name = "1", "Upper bounds of relative humidity bins"
    v[:] = RH_UPPER
    v = d.createVariable("code_hydrophilic", "S1", ("hydrophilic", "code_str"))
    v.long_name = "Hydrophilic aerosol code"
    v[:] = chars(CODES_PHILIC)
    v = d.createVariable("code_hydrophobic", "S1", ("hydrophobic", "code_str"))
    v.long_name = "Hydrophobic aerosol code"
    v[:] = chars(CODES_PHOBIC)

    x = WAVELENGTH_M / 532e-9
    h = 0.5 * (RH_LOWER + RH_UPPER)
    ext_philic = np.zeros((len(CODES_PHILIC), len(h), len(x)))
    lr_philic = np.zeros_like(ext_philic)
    for t in range(len(CODES_PHILIC)):
        for r in range(len(h)):
            ext_philic[t, r], lr_philic[t, r] = philic(t + 1, h[r], x)
    ext_phobic = np.zeros((len(CODES_PHOBIC), len(x)))
    lr_phobic = np.zeros_like(ext_phobic)
    for t in range(len(CODES_PHOBIC)):
        ext_phobic[t], lr_phobic[t] = phobic(t + 1, x)

    dims_philic = ("hydrophilic", "relative_humidity", "wavelength_mono")
    for name, units, long_name, dims, data in [
        ("mass_ext_mono_hydrophilic", "m2 kg-1", "mass-extinction coefficient of hydrophilic aerosols at selected wavelengths", dims_philic, ext_philic),
        ("lidar_ratio_mono_hydrophilic", "sr", "lidar ratio of hydrophilic aerosols at selected wavelengths", dims_philic, lr_philic),
        ("mass_ext_mono_hydrophobic", "m2 kg-1", "mass-extinction coefficient of hydrophobic aerosols at selected wavelengths", ("hydrophobic", "wavelength_mono"), ext_phobic),
        # ECMWF's file gives this one units "1"
        ("lidar_ratio_mono_hydrophobic", "1", "lidar ratio of hydrophobic aerosols at selected wavelengths", ("hydrophobic", "wavelength_mono"), lr_phobic),
    ]:
        v = d.createVariable(name, "f4", dims)
        v.units, v.long_name = units, long_name
        v[:] = data
    d.close()
    print(f"wrote {OUT} ({OUT.stat().st_size} bytes)")


if __name__ == "__main__":
    main()
