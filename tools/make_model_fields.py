#!/usr/bin/env python3
"""Writes the small ERA5-like model fields of configs/fields/ (docs/scenes.md "Model
fields"): a warm front's sloping cloud band (liquid below, ice above) crossing the
CALIOP-like descending pass of configs/instruments/caliop_fields.toml, and a
stratocumulus-topped boundary layer south of it, over the western Mediterranean
(30-45 N, 8 W-6 E) on 2024-01-15 at 00 and 01 UTC.

  era5_like_model_levels.nc      netCDF-4 (HDF5, zlib): 40 hybrid model levels
                                 (hyam, hybm: our own coefficients, not ECMWF's L137),
                                 t, q, clwc, ciwc, cc per level, sp and z at the surface
  era5_like_pressure_levels.nc   netCDF-3 classic: 20 pressure levels, the same
                                 atmosphere with z (geopotential) per level; t packed as
                                 int16 with scale_factor / add_offset as CDS files are
  cams_like_model_levels.nc      netCDF-4: CAMS-like aerosol mass mixing ratios on the
                                 model-level file's grid, levels and times (aermr01-03
                                 sea salt below 1 km, aermr04-06 a dust plume at 2-5 km
                                 south of 36 N, aermr11 sulphate everywhere)

The numbers are made up to look like a mid-latitude winter night, not taken from ERA5.
Latitudes run north to south and levels top down, as in ERA5 files.

    /tmp/venv/bin/python tools/make_model_fields.py [OUTDIR]

With --global DEG it writes instead one big model-level file, era5_like_global.nc, for
the scale bench (benches/fields_whole_day.sh, issue 39): a global grid of DEG degrees
(0.25: 1440 x 721, longitudes 0 to 360 - DEG east as ERA5's, latitudes 90 N to 90 S),
--levels hybrid levels of the same family as the small file's, at --hours past
2024-01-15 00 UTC; float32, zlib level 1 with shuffle, chunked (1, levels, 60, 60):

    /tmp/venv/bin/python tools/make_model_fields.py --global 0.25 \
        --hours 0,6,12,18,24 --levels 37 OUTDIR

Its atmosphere is made up the same way, vectorised over the globe one level at a time:
a lapse-rate temperature by latitude, an ITCZ of ice-topped deep cloud wandering about
6 N, mid-latitude frontal bands near 45 N and 50 S whose slope and position wave with
longitude and move east in time, and stratocumulus decks at 0.8-1.3 km over the
subtropics (15-30 N and S) where a longitude pattern says "ocean".
"""

import argparse
import sys
from pathlib import Path

import numpy as np
import netCDF4

G0 = 9.80665
OUT = Path(__file__).resolve().parents[1] / "configs" / "fields"
LAT = np.arange(45.0, 29.5, -1.0)          # 16, north to south
LON = np.arange(-8.0, 6.5, 1.0)            # 15
HOURS = np.array([1087296.0, 1087297.0])   # hours since 1900-01-01: 2024-01-15 00 and 01 UTC
TIME_UNITS = "hours since 1900-01-01 00:00:00.0"


def surface(hour, lat, lon):
    """Surface pressure (Pa) and height (m) on (lat, lon)."""
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    hill = 600.0 * np.exp(-((la - 40.0) ** 2 + (lo + 4.0) ** 2) / 2.0)   # a plateau inland
    ps = 101500.0 - 150.0 * (la - 30.0) + 40.0 * lo + 60.0 * hour - 11.5 * hill
    return ps, hill


def atmosphere(p, ps, hill, hour, lat, lon):
    """t, q, clwc, ciwc, cc at pressure p (Pa), broadcast over (lat, lon)."""
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    z = hill - 7400.0 * np.log(p / ps)               # rough height for the shapes, m
    t_sfc = 290.0 - 0.6 * (la - 30.0) + 0.05 * lo + 0.8 * hour
    t = np.where(z < 11000.0, t_sfc - 6.5e-3 * z, t_sfc - 6.5e-3 * 11000.0 + 1e-3 * (z - 11000.0))
    q = 0.009 * np.exp(-z / 2300.0) * np.exp(-(la - 30.0) / 25.0)
    # the warm front: its surface position moves north 0.5 deg/h; the cloud rises
    # from 1.5 km at the front to 9 km 4 deg north of it, 2.5 km deep
    front = 35.5 + 0.15 * lo + 0.5 * hour
    north = la - front
    base = 1500.0 + 1875.0 * north
    inside = (north > 0.0) & (north < 4.0) & (z > base) & (z < base + 2500.0)
    shape = np.where(inside, np.sin(np.pi * np.clip((z - base) / 2500.0, 0, 1)), 0.0)
    liquid_part = np.clip((t - 253.0) / 15.0, 0.0, 1.0)          # all ice below -20 C
    clwc = 3e-4 * shape * liquid_part
    ciwc = 1.5e-5 * shape * (1.0 - liquid_part)
    # the boundary layer south of 33.5 N: a stratocumulus deck at 0.8-1.3 km
    sc = (la < 33.5) & (z > 800.0) & (z < 1300.0)
    clwc = clwc + np.where(sc, 2.5e-4 * np.sin(np.pi * (z - 800.0) / 500.0), 0.0)
    cc = np.where((clwc + ciwc) > 0.0, np.where(sc, 0.8, 1.0), 0.0)
    return t, q, clwc, ciwc, cc


def model_levels(n=40):
    """Our own n hybrid levels: p = a + b*ps with b = eta**2, a = 1e5*(eta - b)."""
    s = np.linspace(1.0, 0.0, n, endpoint=False)[::-1]      # top down
    zl = 32000.0 * (1.0 - s) ** 1.7 + 15.0
    eta = np.exp(-zl / 7400.0)
    b = eta ** 2
    a = 1e5 * (eta - b)
    return a, b


def axes(nc, nlev, lev_values, lev_attrs):
    nc.createDimension("time", None)
    nc.createDimension("level", nlev)
    nc.createDimension("latitude", len(LAT))
    nc.createDimension("longitude", len(LON))
    v = nc.createVariable("time", "i4", ("time",))
    v.units, v.calendar, v.long_name = TIME_UNITS, "gregorian", "time"
    v.standard_name, v.axis = "time", "T"
    v[:] = HOURS.astype("i4")
    v = nc.createVariable("level", "f4" if "units" in lev_attrs and lev_attrs["units"] == "millibars" else "i4", ("level",))
    for k, x in lev_attrs.items():
        setattr(v, k, x)
    v[:] = lev_values
    v = nc.createVariable("latitude", "f4", ("latitude",))
    v.units, v.long_name = "degrees_north", "latitude"
    v.standard_name, v.axis = "latitude", "Y"
    v[:] = LAT
    v = nc.createVariable("longitude", "f4", ("longitude",))
    v.units, v.long_name = "degrees_east", "longitude"
    v.standard_name, v.axis = "longitude", "X"
    v[:] = LON


META = {
    "t": ("K", "Temperature"),
    "q": ("kg kg**-1", "Specific humidity"),
    "clwc": ("kg kg**-1", "Specific cloud liquid water content"),
    "ciwc": ("kg kg**-1", "Specific cloud ice water content"),
    "cc": ("(0 - 1)", "Fraction of cloud cover"),
}


def write_model_levels(path):
    a, b = model_levels()
    nc = netCDF4.Dataset(path, "w", format="NETCDF4")
    nc.Conventions = "CF-1.6"
    nc.history = "made by tools/make_model_fields.py"
    nc.title = "ERA5-like model-level fields (made up; tools/make_model_fields.py)"
    axes(nc, len(a), np.arange(1, len(a) + 1), {"units": "1", "long_name": "model_level_number"})
    for name, vals, units in (("hyam", a, "Pa"), ("hybm", b, "1")):
        v = nc.createVariable(name, "f8", ("level",))
        v.units, v.long_name = units, f"hybrid coefficient {name[-2]} at full levels"
        v[:] = vals
    shape = (len(HOURS), len(a), len(LAT), len(LON))
    data = {k: np.zeros(shape) for k in META}
    sp = np.zeros((len(HOURS), len(LAT), len(LON)))
    for i, _ in enumerate(HOURS):
        ps, hill = surface(float(i), LAT, LON)
        sp[i] = ps
        for k in range(len(a)):
            fields = atmosphere(a[k] + b[k] * ps, ps, hill, float(i), LAT, LON)
            for name, f in zip(META, fields):
                data[name][i, k] = f
    for name, (units, long) in META.items():
        v = nc.createVariable(name, "f4", ("time", "level", "latitude", "longitude"), zlib=True, complevel=6)
        v.units, v.long_name = units, long
        v[:] = data[name]
    v = nc.createVariable("sp", "f4", ("time", "latitude", "longitude"), zlib=True)
    v.units, v.long_name = "Pa", "Surface pressure"
    v[:] = sp
    v = nc.createVariable("z", "f4", ("time", "latitude", "longitude"), zlib=True)
    v.units, v.long_name = "m**2 s**-2", "Geopotential (surface)"
    v[:] = np.stack([surface(float(i), LAT, LON)[1] * G0 for i, _ in enumerate(HOURS)])
    nc.close()


def write_pressure_levels(path):
    plev = np.array([20, 30, 50, 70, 100, 150, 200, 250, 300, 400, 500, 600, 700, 800, 850, 900, 925, 950, 975, 1000.0])
    nc = netCDF4.Dataset(path, "w", format="NETCDF3_CLASSIC")
    nc.Conventions = "CF-1.6"
    nc.history = "made by tools/make_model_fields.py"
    nc.title = "ERA5-like pressure-level fields (made up; tools/make_model_fields.py)"
    axes(nc, len(plev), plev, {"units": "millibars", "long_name": "pressure_level"})
    shape = (len(HOURS), len(plev), len(LAT), len(LON))
    data = {k: np.zeros(shape) for k in META}
    geo = np.zeros(shape)
    for i, _ in enumerate(HOURS):
        ps, hill = surface(float(i), LAT, LON)
        for k, p in enumerate(plev * 100.0):
            pp = np.minimum(p, ps)                  # below ground: the surface's values
            fields = atmosphere(pp, ps, hill, float(i), LAT, LON)
            for name, f in zip(META, fields):
                data[name][i, k] = f
            tv = fields[0] * (1.0 + 0.6078 * fields[1])
            geo[i, k] = G0 * hill + 287.0597 * tv * np.log(ps / p)
    for name, (units, long) in META.items():
        if name == "t":
            lo, hi = data[name].min(), data[name].max()
            scale = (hi - lo) / 65000.0
            offset = 0.5 * (hi + lo)
            v = nc.createVariable(name, "i2", ("time", "level", "latitude", "longitude"))
            v.set_auto_maskandscale(False)
            v.scale_factor, v.add_offset = scale, offset
            v.units, v.long_name = units, long
            v[:] = np.round((data[name] - offset) / scale).astype("i2")
        else:
            v = nc.createVariable(name, "f4", ("time", "level", "latitude", "longitude"))
            v.units, v.long_name = units, long
            v[:] = data[name]
    v = nc.createVariable("z", "f4", ("time", "level", "latitude", "longitude"))
    v.units, v.long_name = "m**2 s**-2", "Geopotential"
    v[:] = geo
    nc.close()


# CAMS-like aerosol (kg kg**-1): species, share of its group, and the group's shape
SEA_SALT = {"aermr01": 0.1, "aermr02": 0.4, "aermr03": 0.5}
DUST = {"aermr04": 0.1, "aermr05": 0.3, "aermr06": 0.6}
LONG = {
    "aermr01": "Sea Salt Aerosol (0.03 - 0.5 um) Mixing Ratio",
    "aermr02": "Sea Salt Aerosol (0.5 - 5 um) Mixing Ratio",
    "aermr03": "Sea Salt Aerosol (5 - 20 um) Mixing Ratio",
    "aermr04": "Dust Aerosol (0.03 - 0.55 um) Mixing Ratio",
    "aermr05": "Dust Aerosol (0.55 - 0.9 um) Mixing Ratio",
    "aermr06": "Dust Aerosol (0.9 - 20 um) Mixing Ratio",
    "aermr11": "Sulphate Aerosol Mixing Ratio",
}


def aerosol(p, ps, hill, lat, lon):
    """The species' mass mixing ratios at pressure p (Pa) over (lat, lon)."""
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    z = hill - 7400.0 * np.log(p / ps)
    sea = hill < 50.0
    salt = np.where(sea & (z < 1000.0), 3e-8, 0.0)
    plume = np.where((la < 36.0) & (z > 2000.0) & (z < 5000.0), 1.5e-7 * np.sin(np.pi * (z - 2000.0) / 3000.0) ** 2, 0.0) * np.where(sea, 1.0, 0.0)
    out = {k: w * salt for k, w in SEA_SALT.items()}
    out.update({k: w * plume for k, w in DUST.items()})
    out["aermr11"] = 1e-9 * np.exp(-np.maximum(z, 0.0) / 3000.0) + 0.0 * la
    return out


def write_cams_levels(path):
    a, b = model_levels()
    nc = netCDF4.Dataset(path, "w", format="NETCDF4")
    nc.Conventions = "CF-1.6"
    nc.history = "made by tools/make_model_fields.py"
    nc.title = "CAMS-like aerosol on the ERA5-like model levels (made up; tools/make_model_fields.py)"
    axes(nc, len(a), np.arange(1, len(a) + 1), {"units": "1", "long_name": "model_level_number"})
    shape = (len(HOURS), len(a), len(LAT), len(LON))
    data = {k: np.zeros(shape) for k in LONG}
    for i, _ in enumerate(HOURS):
        ps, hill = surface(float(i), LAT, LON)
        for k in range(len(a)):
            for name, f in aerosol(a[k] + b[k] * ps, ps, hill, LAT, LON).items():
                data[name][i, k] = f
    for name, long in LONG.items():
        v = nc.createVariable(name, "f4", ("time", "level", "latitude", "longitude"), zlib=True, complevel=9, shuffle=True)
        v.units, v.long_name = "kg kg**-1", long
        v[:] = data[name]
    nc.close()


def global_surface(hour, la, lo):
    """Surface pressure (Pa) and height (m) on the global grid (la, lo float32)."""
    hill = 1500.0 * np.exp(-((la - 35.0) ** 2 + ((lo - 90.0 + 180.0) % 360.0 - 180.0) ** 2 / 4.0) / 50.0)
    hill = hill + 800.0 * np.exp(-((la + 20.0) ** 2 + ((lo - 290.0 + 180.0) % 360.0 - 180.0) ** 2 / 9.0) / 30.0)
    ps = 101300.0 + 800.0 * np.cos(np.radians(2.0 * la)) * np.sin(np.radians(lo + 15.0 * hour)) - 11.5 * hill
    return ps.astype(np.float32), hill.astype(np.float32)


def global_atmosphere(p, ps, hill, hour, la, lo):
    """t, q, clwc, ciwc, cc (float32) at pressure p (Pa) over the global grid."""
    z = hill - 7400.0 * np.log(p / ps)
    t_sfc = 300.0 - 40.0 * np.sin(np.radians(la)) ** 2 + 2.0 * np.cos(np.radians(lo - 15.0 * hour))
    t = np.where(z < 11000.0, t_sfc - 6.5e-3 * z, t_sfc - 6.5e-3 * 11000.0 + 1e-3 * (z - 11000.0))
    q = 0.018 * np.exp(-z / 2300.0) * np.cos(np.radians(la)) ** 2
    liquid_part = np.clip((t - 253.0) / 15.0, 0.0, 1.0)
    shape = np.zeros_like(z)
    # the ITCZ: deep cloud 1-14 km in a 6 deg band about 6 N, gappy in longitude
    itcz = 6.0 + 3.0 * np.sin(np.radians(2.0 * lo))
    deep = (np.abs(la - itcz) < 3.0) & (np.sin(np.radians(7.0 * lo + 30.0 * hour)) > 0.0)
    shape = np.where(deep & (z > 1000.0) & (z < 14000.0), np.sin(np.pi * np.clip((z - 1000.0) / 13000.0, 0, 1)), shape)
    # mid-latitude fronts: bands rising poleward from 1.5 km to 9 km over 4 deg, 2.5 km deep
    for centre, pole in ((45.0, 1.0), (-50.0, -1.0)):
        front = centre + 5.0 * np.sin(np.radians(3.0 * (lo - 10.0 * hour)))
        north = pole * (la - front)
        base = 1500.0 + 1875.0 * north
        inside = (north > 0.0) & (north < 4.0) & (z > base) & (z < base + 2500.0)
        shape = np.where(inside, np.sin(np.pi * np.clip((z - base) / 2500.0, 0, 1)), shape)
    clwc = 3e-4 * shape * liquid_part
    ciwc = 1.5e-5 * shape * (1.0 - liquid_part)
    # subtropical stratocumulus decks at 0.8-1.3 km where "ocean"
    ocean = (hill < 50.0) & (np.sin(np.radians(lo * 2.0)) > -0.3)
    sc = ocean & (np.abs(la) > 15.0) & (np.abs(la) < 30.0) & (z > 800.0) & (z < 1300.0)
    clwc = clwc + np.where(sc, 2.5e-4 * np.sin(np.pi * (z - 800.0) / 500.0), 0.0)
    cc = np.where((clwc + ciwc) > 0.0, np.where(sc, 0.8, 1.0), 0.0)
    return [np.asarray(x, dtype=np.float32) for x in (t, q, clwc, ciwc, cc)]


def write_global(path, deg, hours, nlev):
    """The global model-level file (see the module's doc)."""
    global LAT, LON, HOURS
    LAT = np.linspace(90.0, -90.0, int(round(180.0 / deg)) + 1)
    LON = np.arange(int(round(360.0 / deg))) * deg
    HOURS = 1087296.0 + np.asarray(hours, dtype=float)
    a, b = model_levels(nlev)
    nc = netCDF4.Dataset(path, "w", format="NETCDF4")
    nc.Conventions = "CF-1.6"
    nc.history = "made by tools/make_model_fields.py --global"
    nc.title = "ERA5-like global model-level fields (made up; tools/make_model_fields.py)"
    axes(nc, nlev, np.arange(1, nlev + 1), {"units": "1", "long_name": "model_level_number"})
    for name, vals, units in (("hyam", a, "Pa"), ("hybm", b, "1")):
        v = nc.createVariable(name, "f8", ("level",))
        v.units, v.long_name = units, f"hybrid coefficient {name[-2]} at full levels"
        v[:] = vals
    opts = dict(zlib=True, complevel=1, shuffle=True)
    vs = {}
    for name, (units, long) in META.items():
        v = nc.createVariable(name, "f4", ("time", "level", "latitude", "longitude"), chunksizes=(1, nlev, 60, 60), **opts)
        v.units, v.long_name = units, long
        vs[name] = v
    vsp = nc.createVariable("sp", "f4", ("time", "latitude", "longitude"), chunksizes=(1, 60, 60), **opts)
    vsp.units, vsp.long_name = "Pa", "Surface pressure"
    vz = nc.createVariable("z", "f4", ("time", "latitude", "longitude"), chunksizes=(1, 60, 60), **opts)
    vz.units, vz.long_name = "m**2 s**-2", "Geopotential (surface)"
    la, lo = np.meshgrid(LAT.astype(np.float32), LON.astype(np.float32), indexing="ij")
    for i, h in enumerate(hours):
        ps, hill = global_surface(float(h), la, lo)
        vsp[i] = ps
        vz[i] = hill * G0
        block = {k: np.empty((nlev,) + la.shape, np.float32) for k in META}
        for k in range(nlev):
            for name, f in zip(META, global_atmosphere(np.float32(a[k]) + np.float32(b[k]) * ps, ps, hill, float(h), la, lo)):
                block[name][k] = f
        for name in META:
            vs[name][i] = block[name]
        print(f"  hour {h}: written", flush=True)
    nc.close()


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description="ERA5-like made-up model fields")
    ap.add_argument("outdir", nargs="?", type=Path, default=OUT)
    ap.add_argument("--global", dest="global_deg", type=float, help="write era5_like_global.nc on a global grid of this spacing, degrees")
    ap.add_argument("--hours", default="0,6,12,18,24", help="with --global: hours past 2024-01-15 00 UTC")
    ap.add_argument("--levels", type=int, default=37, help="with --global: number of hybrid levels")
    args = ap.parse_args()
    OUT = args.outdir
    if args.global_deg is not None:
        OUT.mkdir(parents=True, exist_ok=True)
        f = OUT / "era5_like_global.nc"
        write_global(f, args.global_deg, [float(h) for h in args.hours.split(",")], args.levels)
        print(f, f.stat().st_size, "bytes")
        sys.exit(0)
    OUT.mkdir(parents=True, exist_ok=True)
    write_model_levels(OUT / "era5_like_model_levels.nc")
    write_pressure_levels(OUT / "era5_like_pressure_levels.nc")
    write_cams_levels(OUT / "cams_like_model_levels.nc")
    for f in sorted(OUT.glob("*_like_*_levels.nc")):
        print(f, f.stat().st_size, "bytes")
