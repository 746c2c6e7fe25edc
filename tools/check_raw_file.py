#!/usr/bin/env python3
"""Check a lidarsim raw lidar file (HDF5 / netCDF-4) against the interface contract.

Usage: check_raw_file.py FILE.h5 [--structure-only] [--no-ncdump]

Reads the file with h5py, with xarray through h5netcdf and (if installed) netCDF4,
and with `ncdump -h` (if on PATH), and checks that:
  * every dataset is readable and has CF `units` and `long_name` attributes;
  * `counts` is a 3-D unsigned-integer (profile, channel, bin) variable, and the
    optional signal/background/dark components have its shape and type and sum to it;
  * the dimensions are named exactly `profile`, `channel` and `bin` (no `phony_dim_*`)
    in every reader, with the same lengths;
  * format version 2: text attributes come back from h5py as `str`; xarray decodes
    `time` to datetime64 and attaches `time`, `altitude` and `range` as coordinates with
    no extra arguments; `expected_signal = lidar_constant * attenuated_backscatter *
    range_weight`; `expected_counts` is the sum of the three expectations (at most
    that sum for a channel with dead time);
  * the root attributes are readable, and (unless --structure-only) every variable
    and root attribute named in docs/file-format.md is present.
Prints one line per failed check and a summary; exits 1 if any check failed, 2 if the
file or a required Python package cannot be opened at all.
"""

import argparse
import os
import shutil
import subprocess
import sys

REQUIRED_VARIABLES = [
    "counts", "channel", "altitude", "range", "time", "n_shots", "pulse_energy",
    "expected_signal", "expected_background", "expected_dark", "expected_counts", "snr_eq4",
    "lidar_constant", "range_weight", "attenuated_backscatter",
]
REQUIRED_ROOT_ATTRIBUTES = ["Conventions", "title", "source", "history", "date_created", "config",
                            "seed", "method", "lidarsim_format_version"]
COMPONENTS = ["signal_counts", "background_counts", "dark_counts"]
DIMS = ("profile", "channel", "bin")
# variables that need no units: string coordinates
NO_UNITS = {"channel"}


class Checker:
    def __init__(self):
        self.passed = 0
        self.failed = 0

    def check(self, ok, what):
        if ok:
            self.passed += 1
        else:
            self.failed += 1
            print(f"FAIL: {what}")
        return ok


def as_text(value):
    """h5py returns fixed-length string attributes as bytes: decode them."""
    if isinstance(value, bytes):
        return value.decode("utf-8")
    if hasattr(value, "dtype") and value.dtype.kind == "S" and value.shape == ():
        return bytes(value).decode("utf-8")
    return value


def check_h5py(path, c, structure_only):
    import h5py
    import numpy as np

    dims = {}
    with h5py.File(path, "r") as f:
        datasets = {}

        def collect(name, obj):  # must return None, or visititems stops
            if isinstance(obj, h5py.Dataset):
                datasets[name] = obj

        f.visititems(collect)
        c.check(len(datasets) > 0, "h5py: the file holds no dataset")
        data = {}
        for name, ds in datasets.items():
            try:
                data[name] = ds[()]
            except Exception as e:  # noqa: BLE001 - report any read failure
                c.check(False, f"h5py: cannot read dataset {name}: {e}")
                continue
            c.check(True, "")
            for attr in ("units", "long_name"):
                if attr == "units" and name in NO_UNITS:
                    continue
                value = ds.attrs.get(attr)
                c.check(isinstance(value, str) and value != "", f"h5py: {name} has no str attribute {attr!r}")
        for name, value in f.attrs.items():
            c.check(not isinstance(value, bytes), f"h5py: root attribute {name} comes back as bytes, not str")
        if not structure_only:
            for name in REQUIRED_VARIABLES:
                c.check(name in datasets, f"h5py: required variable {name!r} missing")
            for name in REQUIRED_ROOT_ATTRIBUTES:
                c.check(name in f.attrs, f"h5py: required root attribute {name!r} missing")
        if "Conventions" in f.attrs:
            c.check(str(as_text(f.attrs["Conventions"])).startswith("CF-"), "h5py: Conventions is not CF-x.y")

        if c.check("counts" in data, "h5py: no counts dataset"):
            counts = data["counts"]
            c.check(counts.ndim == 3, f"h5py: counts has {counts.ndim} dimensions, not 3")
            c.check(counts.dtype.kind == "u", f"h5py: counts has type {counts.dtype}, not unsigned")
            if counts.ndim == 3:
                dims = dict(zip(DIMS, counts.shape))
            present = [n for n in COMPONENTS if n in data]
            if present:
                c.check(len(present) == 3, f"h5py: only some components present: {present}")
                total = np.zeros(counts.shape, dtype=np.uint64)
                for n in present:
                    c.check(data[n].shape == counts.shape and data[n].dtype == counts.dtype,
                            f"h5py: {n} is {data[n].dtype}{data[n].shape}, counts {counts.dtype}{counts.shape}")
                    if data[n].shape == counts.shape:
                        total += data[n].astype(np.uint64)
                if len(present) == 3:
                    c.check(np.array_equal(total, counts.astype(np.uint64)),
                            "h5py: signal + background + dark counts != counts")
        if not structure_only and all(n in data for n in REQUIRED_VARIABLES):
            model = data["lidar_constant"][:, None] * data["attenuated_backscatter"] * data["range_weight"][None, :]
            c.check(np.allclose(model, data["expected_signal"], rtol=1e-9, atol=0),
                    "h5py: expected_signal != lidar_constant * attenuated_backscatter * range_weight")
            total = data["expected_signal"] + data["expected_background"] + data["expected_dark"]
            # a channel with dead time records less than arrives; an ideal one all of it
            # (channel, bin), or (profile, channel, bin) in a scene that changes along the track
            channels = data["lidar_constant"].shape[0]
            dead = f["dead_time"][:] > 0 if "dead_time" in f else np.zeros(channels, bool)
            counted = data["expected_counts"]
            ideal_ok = np.allclose(total[..., ~dead, :], counted[..., ~dead, :], rtol=1e-9, atol=0)
            c.check(bool(ideal_ok), "h5py: expected_counts != signal + background + dark (ideal detector)")
            c.check(bool(np.all(counted[..., dead, :] <= total[..., dead, :] * (1 + 1e-9))),
                    "h5py: expected_counts above signal + background + dark (dead time)")
            c.check(int(f.attrs["lidarsim_format_version"]) == 2, "h5py: lidarsim_format_version is not 2")
        for name in DIMS:
            if name in f:
                c.check(f[name].attrs.get("CLASS") is not None and as_text(f[name].attrs["CLASS"]) == "DIMENSION_SCALE",
                        f"h5py: {name} is not a dimension scale")
    return dims


def check_xarray(path, engine, c, dims):
    import xarray as xr

    try:
        ds = xr.open_dataset(path, engine=engine)
    except Exception as e:  # noqa: BLE001
        c.check(False, f"xarray[{engine}]: cannot open: {e}")
        return
    with ds:
        names = list(ds.sizes)
        c.check(not any(n.startswith("phony_dim") for n in names), f"xarray[{engine}]: phony dimensions {names}")
        c.check(set(names) == set(DIMS), f"xarray[{engine}]: dimensions are {names}, expected {list(DIMS)}")
        for n, size in dims.items():
            c.check(ds.sizes.get(n) == size, f"xarray[{engine}]: dimension {n} has size {ds.sizes.get(n)}, expected {size}")
        if "counts" in ds:
            c.check(ds["counts"].dims == DIMS, f"xarray[{engine}]: counts has dims {ds['counts'].dims}")
        c.check(str(ds["time"].dtype).startswith("datetime64"),
                f"xarray[{engine}]: time is {ds['time'].dtype}, not datetime64")
        for coord in ("time", "altitude", "range"):
            c.check(coord in ds.coords, f"xarray[{engine}]: {coord} is not a coordinate")
        for name, var in ds.variables.items():
            c.check(set(var.dims) <= set(DIMS), f"xarray[{engine}]: {name} has dims {var.dims}")
            c.check(name in NO_UNITS or bool(var.attrs.get("units")) or bool(var.encoding.get("units")),
                    f"xarray[{engine}]: {name} has no units")
            c.check(bool(var.attrs.get("long_name")), f"xarray[{engine}]: {name} has no long_name")
            var.values  # noqa: B018 - read the data
        for name, value in ds.attrs.items():
            c.check(not isinstance(value, bytes), f"xarray[{engine}]: root attribute {name} came back as bytes")


def check_ncdump(path, c, dims, attr_names):
    ncdump = shutil.which("ncdump")
    if ncdump is None:
        c.check(False, "ncdump not found on PATH (install netcdf-bin, or pass --no-ncdump)")
        return
    run = subprocess.run([ncdump, "-h", path], capture_output=True, text=True)
    if not c.check(run.returncode == 0, f"ncdump -h failed ({run.returncode}): {run.stderr.strip()}"):
        return
    out = run.stdout
    c.check("phony_dim" not in out, "ncdump: phony dimensions")
    for n, size in dims.items():
        c.check(f"\t{n} = {size} ;" in out, f"ncdump: no dimension line '{n} = {size} ;'")
    c.check("counts(profile, channel, bin)" in out, "ncdump: counts is not (profile, channel, bin)")
    for name in attr_names:
        # NC_CHAR attributes show as "\t\t:name = ...", NC_STRING ones as "\t\tstring :name = ...".
        c.check(f":{name} = " in out, f"ncdump: root attribute {name} not shown")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("file")
    p.add_argument("--structure-only", action="store_true",
                   help="skip the check for the variables and root attributes docs/file-format.md requires")
    p.add_argument("--no-ncdump", action="store_true", help="do not run ncdump -h")
    args = p.parse_args()

    if not os.path.isfile(args.file):
        print(f"check_raw_file: {args.file}: no such file", file=sys.stderr)
        return 2
    try:
        import h5py
        import h5netcdf  # noqa: F401
        import xarray  # noqa: F401
    except ImportError as e:
        print(f"check_raw_file: missing Python package: {e} (pip install numpy h5py xarray h5netcdf netCDF4)",
              file=sys.stderr)
        return 2

    c = Checker()
    try:
        dims = check_h5py(args.file, c, args.structure_only)
    except OSError as e:
        print(f"check_raw_file: {args.file}: cannot open with h5py: {e}", file=sys.stderr)
        return 2
    with h5py.File(args.file, "r") as f:
        attr_names = list(f.attrs)
    check_xarray(args.file, "h5netcdf", c, dims)
    try:
        import netCDF4  # noqa: F401
        check_xarray(args.file, "netcdf4", c, dims)
    except ImportError:
        print("check_raw_file: netCDF4 not installed, skipping the netCDF-C reader via xarray")
    if not args.no_ncdump:
        check_ncdump(args.file, c, dims, attr_names)

    print(f"check_raw_file: {c.passed} passed, {c.failed} failed")
    return 1 if c.failed else 0


if __name__ == "__main__":
    sys.exit(main())
