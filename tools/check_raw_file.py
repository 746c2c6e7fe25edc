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
  * format version 5: `channel` numbers the channels 0, 1, ... (int), `channel_name`
    holds their distinct names (strings), every other variable with the channel
    dimension lists `channel_name` in its `coordinates` attribute, xarray attaches it as
    a coordinate, and `ds.set_xindex("channel_name").sel(channel_name=NAME)` is
    `ds.isel(channel=K)` (formats 2 to 4: `channel` the names);
  * format version 4 and later (3 and 2 are read as older formats): `pulse_energy` is (profile,
    channel), finite and >= 0, each channel's at its own laser line (a channel's
    `pulse_energy / nominal_pulse_energy` is the profile's energy factor, shared by
    every channel: one laser's shots; 1e-12); text attributes come back from h5py as `str`; xarray decodes
    `time` to datetime64 and attaches `time`, `altitude` and `range` as coordinates with
    no extra arguments; `expected_signal = lidar_constant * attenuated_backscatter *
    range_weight`; `expected_counts` is the sum of the three expectations (at most
    that sum for a channel with dead time); these per profile, rebuilt here from
    whatever form the file holds (format 4's compact truth: `expected_signal` and
    `attenuated_backscatter` per column, `expected_background` per (profile, channel),
    no `expected_counts` of an ideal detector, no `snr_eq4`; docs/file-format.md, "The
    truth of each profile"), and per column where they are per column;
  * the truth (format 3): per column, channel and bin `alpha_total` is the sum of
    `alpha_mol`, `alpha_o3`, `alpha_aer`, `alpha_cld` (1e-12), `beta_mol` times
    `molecular_lidar_ratio` is `alpha_mol` (1e-12), the particle lidar ratios are
    `alpha/beta` where the species is present, `number_density = pressure /
    (k_B temperature)` (1e-12) where they are given, `t2` is in (0, 1]; every profile's
    `profile_column` are columns of the file (or -1 with weight 0), its
    `profile_column_weight` in [0, 1] summing to 1 (1e-12); and the xarray recipe of
    docs/file-format.md expands the truth to (profile, channel, bin);
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

TRUTH = ["alpha_mol", "alpha_aer", "alpha_cld", "alpha_o3", "alpha_total", "beta_mol", "beta_aer",
         "beta_cld", "lidar_ratio_aer", "lidar_ratio_cld", "ms_factor_aer", "ms_factor_cld", "depol_aer",
         "depol_cld", "depol_mol", "depol_volume", "t2"]
STATE = ["pressure", "temperature", "number_density"]
CHANNEL_TEXT = ["channel_kind", "channel_species", "polarization", "detection_mode", "acquisition_mode",
                "glue_partner", "dead_time_model",
                "molecular_line"]
REQUIRED_VARIABLES = [
    "counts", "channel", "altitude", "range", "time", "n_shots", "pulse_energy",
    "expected_signal", "expected_background", "expected_dark", "lidar_constant", "range_weight", "attenuated_backscatter",
    "overlap", "emission_wavelength", "detection_wavelength", "crosstalk", "relative_gain",
    "filter_width", "molecular_transmission", "particle_transmission", "molecular_lidar_ratio",
    "profile_column", "profile_column_weight", "column", "k",
] + TRUTH + STATE + CHANNEL_TEXT
K_B = 1.380649e-23  # J/K, CODATA 2018 (exact)
REQUIRED_ROOT_ATTRIBUTES = ["Conventions", "title", "source", "history", "date_created", "config",
                            "seed", "method", "lidarsim_format_version", "full_overlap_range_m"]
COMPONENTS = ["signal_counts", "background_counts", "dark_counts"]
DIMS = ("profile", "channel", "bin")
# the format-3 dimensions of the truth: the scene's columns and a profile's column slots
TRUTH_DIMS = ("column", "k")
# variables that need no units: strings
NO_UNITS = {"channel", "channel_name"} | set(CHANNEL_TEXT)


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
            version = int(f.attrs.get("lidarsim_format_version", 0))
            for name in REQUIRED_VARIABLES + (["channel_name"] if version >= 5 else []):
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
            dim_names = {n: tuple(d.values()[0].name.lstrip("/") if len(d) else "" for d in ds.dims)
                         for n, ds in datasets.items()}
            if dim_names.get("expected_signal", ())[:1] == ("column",):
                # the compact truth: the identity per column too
                model = (data["lidar_constant"][None, :, None] * data["attenuated_backscatter"]
                         * data["range_weight"][None, None, :])
                c.check(np.allclose(model, data["expected_signal"], rtol=1e-9, atol=0),
                        "h5py: expected_signal != lidar_constant * attenuated_backscatter * range_weight per column")
            rebuilt = {n: per_profile(data, dim_names, n)
                       for n in ("expected_signal", "expected_background", "expected_dark", "expected_counts",
                                 "snr_eq4", "attenuated_backscatter")}
            for n, v in rebuilt.items():
                c.check(v.shape == counts.shape and bool(np.all(np.isfinite(v))),
                        f"h5py: {n} rebuilt per profile is {v.shape} or not finite")
            model = (data["lidar_constant"][None, :, None] * rebuilt["attenuated_backscatter"]
                     * data["range_weight"][None, None, :])
            c.check(np.allclose(model, rebuilt["expected_signal"], rtol=1e-9, atol=0),
                    "h5py: expected_signal != lidar_constant * attenuated_backscatter * range_weight")
            total = rebuilt["expected_signal"] + rebuilt["expected_background"] + rebuilt["expected_dark"]
            # a channel with dead time records less than arrives; an ideal one all of it
            # (channel, bin), or (profile, channel, bin) in a scene that changes along the track
            channels = data["lidar_constant"].shape[0]
            dead = f["dead_time"][:] > 0 if "dead_time" in f else np.zeros(channels, bool)
            # an analog channel records ADC codes, not photons: neither check applies
            analog = np.zeros(channels, bool)
            if "acquisition_mode" in f:
                modes = [m.decode() if isinstance(m, bytes) else m for m in f["acquisition_mode"][:]]
                analog = np.array([m == "analog" for m in modes])
            dead &= ~analog
            # the detector's own counts, in expected_counts beside the photons
            for extra in ("expected_induced", "expected_afterpulse"):
                if extra in f:
                    total = total + f[extra][:]
            counted = rebuilt["expected_counts"]
            ideal = ~dead & ~analog
            ideal_ok = np.allclose(total[..., ideal, :], counted[..., ideal, :], rtol=1e-9, atol=0)
            c.check(bool(ideal_ok), "h5py: expected_counts != signal + background + dark (ideal detector)")
            c.check(bool(np.all(counted[..., dead, :] <= total[..., dead, :] * (1 + 1e-9))),
                    "h5py: expected_counts above signal + background + dark (dead time)")
            version = int(f.attrs["lidarsim_format_version"])
            c.check(version in (2, 3, 4, 5), f"h5py: lidarsim_format_version {version} is not 2 to 5")
            if version >= 4:
                check_energy(data, c)
            check_truth(data, c)
        check_channel_labels(f, datasets, c)
        for name in DIMS:
            if name in f:
                c.check(f[name].attrs.get("CLASS") is not None and as_text(f[name].attrs["CLASS"]) == "DIMENSION_SCALE",
                        f"h5py: {name} is not a dimension scale")
    return dims


def check_channel_labels(f, datasets, c):
    """Format 5: `channel` 0, 1, ... (integers), `channel_name` distinct strings of the
    same length, listed in the `coordinates` of every other variable with the channel
    dimension; formats 2 to 4: `channel` the distinct names."""
    import numpy as np

    if "channel" not in f:
        return
    version = int(f.attrs.get("lidarsim_format_version", 0))
    channel = f["channel"][()]
    if version < 5:
        names = [as_text(x) for x in channel]
        c.check(all(isinstance(x, str) for x in names), "h5py: channel names (format < 5) are not strings")
        c.check(len(set(names)) == len(names), f"h5py: channel names {names} are not distinct")
        return
    c.check(channel.dtype.kind == "i" and np.array_equal(channel, np.arange(len(channel))),
            f"h5py: channel is {channel.dtype} {channel.tolist()}, not the integers 0 .. n-1")
    if not c.check("channel_name" in f, "h5py: format 5 without channel_name"):
        return
    names = [as_text(x) for x in f["channel_name"][()]]
    c.check(all(isinstance(x, str) and x for x in names) and len(set(names)) == len(names) == len(channel),
            f"h5py: channel_name {names} are not {len(channel)} distinct non-empty strings")
    for name, ds in datasets.items():
        dims = [d.values()[0].name.lstrip("/") if len(d) else "" for d in ds.dims]
        if "channel" in dims and name not in ("channel", "channel_name"):
            coords = str(as_text(ds.attrs.get("coordinates", ""))).split()
            c.check("channel_name" in coords, f"h5py: {name} has the channel dimension but its coordinates {coords} "
                    "do not list channel_name")


def check_energy(data, c):
    """Format 4's per-channel pulse energy: (profile, channel), finite, >= 0, and one energy
    factor per profile that every channel shares (docs/file-format.md)."""
    import numpy as np

    energy, nominal = data["pulse_energy"], data["nominal_pulse_energy"]
    shape = (data["counts"].shape[0], nominal.shape[0])
    if not c.check(energy.shape == shape, f"h5py: pulse_energy is {energy.shape}, not (profile, channel) {shape}"):
        return
    c.check(bool(np.all(np.isfinite(energy)) and np.all(energy >= 0)), "h5py: pulse_energy not finite and >= 0")
    factor = energy / np.where(nominal > 0, nominal, 1)[None, :]
    c.check(rel_dev(factor, np.repeat(factor[:, :1], shape[1], axis=1)) <= 1e-12,
            "h5py: pulse_energy / nominal_pulse_energy differs between channels of a profile")


def per_profile(data, dim_names, name):
    """``name`` of every profile (profile, channel, bin), from whatever form the file holds
    (docs/file-format.md, "The truth of each profile"): (profile, channel, bin) as is,
    (channel, bin) in every profile, (column, channel, bin) mixed by each profile's
    columns, (profile, channel) in every bin; an absent ``expected_counts`` (ideal
    detectors) is signal + background + dark, an absent ``snr_eq4`` Eq. 4 of those."""
    import numpy as np

    p, ch, b = data["counts"].shape
    if name not in data:
        s, bg, d = (per_profile(data, dim_names, n)
                    for n in ("expected_signal", "expected_background", "expected_dark"))
        if name == "expected_counts":
            return s + bg + d
        m = data["n_shots"].astype("float64")[:, None, None]
        total = m * (s + bg + d)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(total > 0, m * s / np.sqrt(total), 0.0)
    v, dims = data[name], dim_names.get(name, ())
    if dims == ("profile", "channel", "bin"):
        return v
    if dims == ("channel", "bin"):
        return np.broadcast_to(v, (p, ch, b))
    if dims == ("profile", "channel"):
        return np.repeat(v[:, :, None], b, axis=2)
    if dims == ("column", "channel", "bin"):
        col, w = np.clip(data["profile_column"], 0, None), data["profile_column_weight"]
        out = np.zeros((p, ch, b))
        for j in range(col.shape[1]):
            out = out + w[:, j, None, None] * v[col[:, j]]
        return out
    return np.full((p, ch, b), np.nan)


def rel_dev(a, b):
    """Largest relative difference of two arrays (0 where both are 0)."""
    import numpy as np

    scale = np.maximum(np.abs(a), np.abs(b))
    return float(np.max(np.where(scale > 0, np.abs(a - b) / np.where(scale > 0, scale, 1), 0), initial=0))


def check_truth(data, c):
    """The identities of the format-3 truth (docs/file-format.md), per column."""
    import numpy as np

    total = data["alpha_mol"] + data["alpha_o3"] + data["alpha_aer"] + data["alpha_cld"]
    c.check(rel_dev(total, data["alpha_total"]) <= 1e-12, "h5py: alpha_total != sum of alpha_*")
    s_mol = data["molecular_lidar_ratio"][None, :, None]
    c.check(rel_dev(data["beta_mol"] * s_mol, data["alpha_mol"]) <= 1e-12,
            "h5py: beta_mol * molecular_lidar_ratio != alpha_mol")
    for species in ("aer", "cld"):
        beta, alpha, ratio = data[f"beta_{species}"], data[f"alpha_{species}"], data[f"lidar_ratio_{species}"]
        present = beta > 0
        c.check(rel_dev(beta[present] * ratio[present], alpha[present]) <= 1e-12,
                f"h5py: lidar_ratio_{species} != alpha_{species} / beta_{species}")
        c.check(bool(np.all(ratio[~present] == 0)), f"h5py: lidar_ratio_{species} not 0 where absent")
    p, t, n = data["pressure"], data["temperature"], data["number_density"]
    given = np.isfinite(p) & np.isfinite(t)
    c.check(rel_dev(n[given], p[given] / (K_B * t[given])) <= 1e-12, "h5py: number_density != p / (k_B T)")
    c.check(bool(np.all(np.isfinite(n)) and np.all(n >= 0)), "h5py: number_density not finite and >= 0")
    t2 = data["t2"]
    c.check(bool(np.all((t2 >= 0) & (t2 <= 1))), "h5py: t2 outside [0, 1]")
    col, w = data["profile_column"], data["profile_column_weight"]
    n_columns = data["alpha_total"].shape[0]
    c.check(bool(np.all((col >= -1) & (col < n_columns))), "h5py: profile_column outside the columns")
    c.check(bool(np.all(w[col < 0] == 0)), "h5py: an unused slot has a weight")
    c.check(bool(np.all((w >= 0) & (w <= 1))), "h5py: profile_column_weight outside [0, 1]")
    c.check(float(np.max(np.abs(w.sum(axis=1) - 1), initial=0)) <= 1e-12,
            "h5py: profile_column_weight does not sum to 1")


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
        c.check(set(DIMS) <= set(names) <= set(DIMS + TRUTH_DIMS),
                f"xarray[{engine}]: dimensions are {names}, expected {list(DIMS + TRUTH_DIMS)}")
        for n, size in dims.items():
            c.check(ds.sizes.get(n) == size, f"xarray[{engine}]: dimension {n} has size {ds.sizes.get(n)}, expected {size}")
        if "counts" in ds:
            c.check(ds["counts"].dims == DIMS, f"xarray[{engine}]: counts has dims {ds['counts'].dims}")
        c.check(str(ds["time"].dtype).startswith("datetime64"),
                f"xarray[{engine}]: time is {ds['time'].dtype}, not datetime64")
        for coord in ("time", "altitude", "range"):
            c.check(coord in ds.coords, f"xarray[{engine}]: {coord} is not a coordinate")
        for name, var in ds.variables.items():
            c.check(set(var.dims) <= set(DIMS + TRUTH_DIMS), f"xarray[{engine}]: {name} has dims {var.dims}")
            c.check(name in NO_UNITS or bool(var.attrs.get("units")) or bool(var.encoding.get("units")),
                    f"xarray[{engine}]: {name} has no units")
            c.check(bool(var.attrs.get("long_name")), f"xarray[{engine}]: {name} has no long_name")
            var.values  # noqa: B018 - read the data
        for name, value in ds.attrs.items():
            c.check(not isinstance(value, bytes), f"xarray[{engine}]: root attribute {name} came back as bytes")
        if "profile_column" in ds and "beta_cld" in ds:
            # the two-line recipe of docs/file-format.md
            col, w = ds.profile_column.clip(min=0), ds.profile_column_weight
            beta = (ds.beta_cld.isel(column=col) * w).sum("k")
            c.check(beta.dims == DIMS, f"xarray[{engine}]: the recipe gives dims {beta.dims}")
            if engine == "h5netcdf":
                import numpy as np
                c.check(bool(np.all(np.isfinite(beta.values))), f"xarray[{engine}]: the recipe gives NaN")
        if "channel_name" in ds.variables:
            # format 5: the names are a coordinate, and the one-call recipe of the README selects by name
            c.check("channel_name" in ds.coords, f"xarray[{engine}]: channel_name is not a coordinate")
            names = ds["channel_name"].values.tolist()
            c.check(all(isinstance(x, str) for x in names), f"xarray[{engine}]: channel_name values are not str")
            by_name = ds.set_xindex("channel_name").sel(channel_name=names[-1])
            c.check(int(by_name["channel"]) == len(names) - 1 and
                    bool((by_name.counts == ds.counts.isel(channel=-1)).all()),
                    f"xarray[{engine}]: set_xindex('channel_name').sel(channel_name=...) is not that channel")
        elif "channel" in ds:
            c.check(all(isinstance(x, str) for x in ds["channel"].values.tolist()),
                    f"xarray[{engine}]: channel names are not str")


def check_ncdump(path, c, dims, attr_names):
    ncdump = shutil.which("ncdump")
    if ncdump is None:
        # optional (README): skipped, and said so, not a failure
        print("check_raw_file: SKIPPED the ncdump -h check: ncdump is not on PATH "
              "(install netcdf-bin to run it)", file=sys.stderr)
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
