"""One curtain from an onboard product (docs/file-format.md, "Stitched curtains").

    import sys; sys.path.insert(0, "tools")
    from product_curtain import stitch
    stitch("p.h5", "532_total").plot(x="time", y="altitude")

`stitch(path, channel)` returns one xarray DataArray (altitude, time) of the channel's
counts per shot and per metre of altitude, `counts / n_shots / vertical_resolution_m`
(with `per_metre=False`: counts per shot, `counts / n_shots`), on a common grid: the
finest region's altitude step and the finest region's profile times. Each region's
value fills every grid cell whose centre lies in that region bin and profile (a 300 m,
15-shot bin fills 10 × 15 cells of a 30 m, 1-shot grid); cells no region of the channel
covers are NaN. Counts per shot and metre are comparable across regions: their
expectation is the mean signal plus background of the cells they cover.

Needs numpy, xarray and h5netcdf (or netCDF4).
"""

import h5py
import numpy as np
import xarray as xr


def _names(group):
    """A region group's channel names: `channel_name` beside the numbered `channel`
    (format 5), or the strings of `channel` (formats 2 to 4)."""
    label = "channel_name" if "channel_name" in group else "channel"
    return list(group[label].asstr()[:])


def _regions(path, channel):
    """The region groups of `path` holding `channel`, in file order."""
    with h5py.File(path, "r") as f:
        names = sorted((g for g in f if g.startswith("region_")), key=lambda g: int(g[7:]))
        return [g for g in names if channel in _names(f[g])]


def _spacing(values, fallback):
    """The mean step of `values` (sorted or not), `fallback` for one value."""
    v = np.sort(np.asarray(values, dtype="float64"))
    return float(np.mean(np.diff(v))) if v.size > 1 else float(fallback)


def stitch(path, channel, per_metre=True):
    """The curtain of `channel` in the onboard product at `path` (see the module)."""
    groups = _regions(path, channel)
    if not groups:
        raise ValueError(f"{path}: no region holds channel {channel!r}")
    parts = []
    for g in groups:
        ds = xr.open_dataset(path, engine="h5netcdf", group=g)
        res_m = float(ds.attrs["vertical_resolution_m"])
        by = "channel_name" if "channel_name" in ds.variables else "channel"
        counts = ds.counts.isel(channel=list(ds[by].values).index(channel))
        counts = counts.astype("float64") / ds.n_shots
        if per_metre:
            counts = counts / res_m
        da = counts.swap_dims(bin="altitude", profile="time").drop_vars(
            [c for c in ("bin", "profile", "channel", "channel_name") if c in counts.coords]
        )
        step_m = abs(_spacing(ds.altitude.values, res_m))
        parts.append((da, step_m, int(ds.attrs["shots_averaged"])))
    fine_m = min(p[1] for p in parts)
    finest = min(parts, key=lambda p: p[2])
    times = finest[0].time.values
    t = times.astype("datetime64[ns]").astype("int64").astype("float64")
    shot_ns = _spacing(t, 1e9) / finest[2]
    lo = min(float(da.altitude.min()) - s / 2 for da, s, _ in parts)
    hi = max(float(da.altitude.max()) + s / 2 for da, s, _ in parts)
    n = int(round((hi - lo) / fine_m))
    altitude = lo + fine_m * (np.arange(n)[::-1] + 0.5)
    curtain = None
    for da, step_m, shots in parts:
        filled = da.reindex(
            altitude=altitude, method="nearest", tolerance=step_m / 2 * (1 + 1e-9)
        ).reindex(
            time=times,
            method="nearest",
            tolerance=np.timedelta64(int(shots * shot_ns / 2), "ns"),
        )
        curtain = filled if curtain is None else curtain.combine_first(filled)
    curtain = curtain.reindex(altitude=altitude).transpose("altitude", "time")
    curtain.name = "counts_per_shot_per_m" if per_metre else "counts_per_shot"
    curtain.attrs = {
        "long_name": f"{channel} counts per shot"
        + (" per metre of altitude" if per_metre else "")
        + ", every region at its own resolution",
        "units": "count m-1" if per_metre else "count",
    }
    curtain.altitude.attrs.update(units="m", long_name="altitude of the grid cell centre")
    return curtain
