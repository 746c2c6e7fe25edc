"""lidarsim in Python: the simulator's commands in the same process, their results as
xarray Datasets (docs/python.md).

    import lidarsim
    cfg = lidarsim.load_config("configs/paper/scenario1.toml",
                               {"instrument.pulse_energy_j": 0.5})
    model = lidarsim.expect(cfg)                  # every channel per bin: the file's truth
    raw = lidarsim.simulate(cfg, profiles=100, seed=1)   # the raw file's Dataset, in memory

Bad input raises ``ValueError`` (files: ``OSError``) with the one-line message the CLI
prints. Long calls release the GIL; Ctrl-C stops them and leaves no file.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import signal
import tempfile
import threading
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence, Union

import numpy as np
import xarray as xr

from . import _lidarsim

__version__: str = _lidarsim.__version__  # the lidarsim crate's (its Cargo.toml)

__all__ = ["__version__", "Config", "load_config", "expect", "simulate", "per_profile", "validate",
           "validate_file", "sweep"]


_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def _toml_key(key: str) -> str:
    """A key of an inline table: bare when TOML allows it, else a quoted string."""
    return key if _BARE_KEY.fullmatch(key) else json.dumps(key)


def _plain(value: Any) -> Any:
    """numpy scalars as the Python number they hold, numpy arrays as (nested) lists."""
    if isinstance(value, np.generic):  # np.float64 is a float, but reprs as np.float64(..)
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    return value


def _toml_value(key: str, value: Any) -> str:
    """A Python value as the TOML of a ``--set KEY=VALUE`` override: booleans, numbers,
    strings, lists and tuples (arrays), dicts (inline tables), numpy scalars and arrays;
    anything else is refused in one line naming the key."""
    value = _plain(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"--set {key}: {value} is not a finite number")
        return repr(float(value))
    if isinstance(value, str):
        return json.dumps(value)  # a TOML basic string
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(key, v) for v in value) + "]"
    if isinstance(value, Mapping):
        for k in value:
            if not isinstance(k, str) or not k:
                raise ValueError(f"--set {key}: the table key {k!r} is not a non-empty string")
        return "{" + ", ".join(f"{_toml_key(k)} = {_toml_value(f'{key}.{k}', v)}"
                               for k, v in value.items()) + "}"
    raise ValueError(f"--set {key}: a Python {type(value).__name__} is not a number, "
                     "boolean, string, list, dict or numpy value")


def _flat(key: str, value: Any) -> list:
    """An override as ``(dotted key, value)`` pairs: a non-empty dict is set key by key
    (merged into the config's table, as ``--set a.b.c=...`` for each of its leaves);
    anything else, a list of dicts too, replaces the value at ``key``."""
    if not isinstance(key, str) or not key or any(not p for p in key.split(".")):
        raise ValueError(f"--set {key!r}: a key is a non-empty dotted string "
                         '("instrument.pulse_energy_j")')
    if isinstance(value, Mapping) and value:
        out = []
        for k, v in value.items():
            if not isinstance(k, str) or not k:
                raise ValueError(f"--set {key}: the table key {k!r} is not a non-empty string")
            out += _flat(f"{key}.{k}", v)
        return out
    return [(key, value)]


@dataclass(frozen=True)
class Config:
    """A scenario config file and dotted-key overrides, loaded and checked once (on the
    first call that needs it) and kept for every later call."""

    path: Path
    overrides: Mapping[str, Any] = field(default_factory=dict)
    _loaded: Any = field(default=None, init=False, repr=False, compare=False)

    def sets(self) -> list:
        """The overrides as the CLI's ``--set KEY=VALUE`` arguments."""
        return [f"{k}={_toml_value(k, v)}"
                for key, value in self.overrides.items() for k, v in _flat(key, value)]

    @property
    def loaded(self) -> "_lidarsim.Loaded":
        """The config loaded and checked, every channel built (raises as the CLI refuses)."""
        if self._loaded is None:
            object.__setattr__(self, "_loaded",
                               _lidarsim.Loaded(os.fspath(self.path), self.sets()))
        return self._loaded

    @property
    def channels(self) -> list:
        """The receiver channels' names."""
        return self.loaded.channels


ConfigLike = Union[Config, str, os.PathLike]


def load_config(path: Union[str, os.PathLike], overrides: Optional[Mapping[str, Any]] = None,
                **keys: Any) -> Config:
    """Loads and checks a config: ``overrides`` maps dotted keys to values
    (``{"instrument.pulse_energy_j": 0.01}``); keyword arguments may spell the dots as
    double underscores (``instrument__pulse_energy_j=0.01``)."""
    o = dict(overrides or {})
    o.update({k.replace("__", "."): v for k, v in keys.items()})
    cfg = Config(Path(path), o)
    _ = cfg.loaded  # raises as the CLI refuses
    return cfg


def _config(config: ConfigLike) -> Config:
    return config if isinstance(config, Config) else Config(Path(config))


_ATTR_TYPES = {"str": str, "u64": np.uint64, "i32": np.int32, "f64": np.float64}


# attributes whose variables xarray's CF decoding changes (masks, scales, times) beyond
# what _dataset does itself: with one of them, xarray decodes the whole Dataset
_DECODED = ("_FillValue", "missing_value", "scale_factor", "add_offset", "calendar")


def _dataset(variables: list, root: list) -> xr.Dataset:
    """The raw file's variables and attributes as xarray reads them from the file: the
    dimensions' own variables as indexes, CF decoding (``time`` as datetime64, the
    ``coordinates`` attributes as coordinates). The numeric arrays are the run's own
    buffers, not copies."""
    def attrs(items):
        return {k: _ATTR_TYPES[tag](v) for k, (tag, v) in items}

    data, coords, decode = {}, set(), False
    for name, dims, values, items in variables:
        if isinstance(values, list):
            values = np.array(values, dtype=object)
        a = attrs(items)
        encoding = {}
        if values.dtype.kind == "f" and np.isnan(a.get("_FillValue", 0.0)):
            encoding["_FillValue"] = a.pop("_FillValue")  # masks nothing NaN is not
        # fastpath: the values are already numpy arrays of the file's types
        var = xr.Variable(dims, values, attrs=a, encoding=encoding, fastpath=True)
        if " since " in str(a.get("units", "")):  # CF time: xarray's own decoder
            var = xr.coders.CFDatetimeCoder().decode(var, name=name)
        decode = decode or any(k in var.attrs for k in _DECODED)
        if not decode and "coordinates" in var.attrs:
            coords.update(var.attrs.pop("coordinates").split())
        data[name] = var
    if decode:  # xarray's own decoding, as its file reader does it (with the
        # coordinates already taken from the variables before the first that needed it)
        ds = xr.decode_cf(xr.Dataset(data, attrs=attrs(root)))
        ds = ds.set_coords([c for c in coords if c in ds.data_vars])
    else:  # nothing else to decode but the coordinates (what decode_cf would do, in a
        # third of its time)
        ds = xr.Dataset({k: v for k, v in data.items() if k not in coords},
                        coords={k: data[k] for k in coords}, attrs=attrs(root))
    return _by_name(ds)


def _by_name(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` with its channels indexed by name too (format 5's numbered ``channel`` and
    its label ``channel_name``): ``ds.sel(channel_name="532_total")`` in one call, as
    ``ds.set_xindex("channel_name")`` gives a Dataset read from a file."""
    if "channel_name" in ds.coords and "channel_name" not in ds.xindexes:
        ds = ds.set_xindex("channel_name")
    return ds


def _one_channel(ds: xr.Dataset, cfg: Config, channel: Optional[str]) -> xr.Dataset:
    if channel is None:
        return ds
    return ds.isel(channel=cfg.loaded.channel_index(channel))  # the CLI's refusal


def expect(config: ConfigLike, channel: Optional[str] = None) -> xr.Dataset:
    """``lidarsim expect``: the deterministic model of every channel per bin, as the raw
    file holds it before its first profile (the same variables, dimensions and
    attributes: ``expected_signal``, ``expected_background``, ``snr_eq4``,
    ``attenuated_backscatter``, the truth of each column, ...), with
    ``snr_bkg_estimated``, the CSV's S/N with an estimated background. With
    ``channel``: that channel only. ``expect --csv``'s numbers to the last bit."""
    cfg = _config(config)
    variables, root, shots = _lidarsim.expect(cfg.loaded)
    ds = _dataset(variables, root)
    ds.attrs.update(config_file=os.fspath(cfg.path), shots_per_profile=shots)
    return _one_channel(ds, cfg, channel)


def simulate(config: ConfigLike, profiles: Optional[int] = None, seed: Optional[int] = None,
             method: Optional[str] = None, path: Union[str, os.PathLike, None] = None,
             progress: bool = False, truth: Optional[str] = None,
             photons: Union[str, os.PathLike, None] = None) -> Union[xr.Dataset, Path]:
    """``lidarsim simulate CONFIG -o PATH``: with ``path``, writes the raw file exactly
    as the CLI does (same seed, same counts and truth) and returns its path; without,
    returns the raw file's Dataset built in memory (no file, no compression; the same
    variables, dimensions and attributes, the counts in the file's integer type).
    ``method``: ``"auto"``, ``"shot"`` or ``"aggregate"``; ``progress``: the CLI's
    progress bar on a terminal; ``truth``: ``"compact"`` (the default,
    ``simulation.truth``) or ``"per-profile"`` (``--truth per-profile``: a changing
    scene's expectations also as format 3's (profile, channel, bin) arrays); ``photons``:
    also write every recorded event to this photon file (``--photons``, docs/photons.md;
    with ``path`` only). Ctrl-C stops
    the run before its next profile and leaves no file. A scene beyond a photon
    counter's range gives a ``UserWarning``."""
    cfg = _config(config)
    profiles, seed = _whole("profiles", profiles), _whole("seed", seed)
    if path is not None:
        with _terminable():
            warning = _lidarsim.simulate(cfg.loaded, os.fspath(path), profiles, seed, method,
                                         truth, progress,
                                         None if photons is None else os.fspath(photons))
        _warn(warning)
        return Path(path)
    if photons is not None:
        raise ValueError("photons are written to a file: give path= too (the raw file's)")
    with _terminable():
        variables, root, warning, _times = _lidarsim.simulate_in_memory(
            cfg.loaded, profiles, seed, method, truth, progress)
    _warn(warning)
    return _dataset(variables, root)


#: The variables ``per_profile`` rebuilds (docs/file-format.md, "The truth of each
#: profile"), and every other (column, channel, bin) variable of the truth.
PER_PROFILE_NAMES = ("expected_signal", "expected_background", "expected_counts", "snr_eq4",
                     "attenuated_backscatter")


def _mix(ds: xr.Dataset, x: xr.DataArray) -> np.ndarray:
    """A (column, channel, bin) variable per profile: ``sum_j w_j * x[c_j]`` over the
    profile's slots in order, from 0 (an unused slot, -1 of weight 0, read as column
    0): the writer's order of operations, so the same bits."""
    cols = np.clip(ds["profile_column"].values, 0, None)
    w = ds["profile_column_weight"].values
    x = x.values
    out = np.zeros((cols.shape[0],) + x.shape[1:])
    for j in range(cols.shape[1]):
        out = out + w[:, j, None, None] * x[cols[:, j]]
    return out


def _as_per_profile(ds: xr.Dataset, name: str) -> np.ndarray:
    """``name`` of every profile, (profile, channel, bin), whatever its form in ``ds``."""
    p, c, b = ds.sizes["profile"], ds.sizes["channel"], ds.sizes["bin"]
    if name not in ds:
        sig = _as_per_profile(ds, "expected_signal")
        bkg = _as_per_profile(ds, "expected_background")
        dark = _as_per_profile(ds, "expected_dark")
        if name == "expected_counts":   # an ideal photon counter: what arrives
            return sig + bkg + dark
        if name == "snr_eq4":           # Eq. 4 with the profile's shots (src/snr.rs)
            m = ds["n_shots"].values.astype("float64")[:, None, None]
            total = m * (sig + bkg + dark)
            with np.errstate(divide="ignore", invalid="ignore"):
                return np.where(total > 0.0, m * sig / np.sqrt(total), 0.0)
        raise KeyError(f"{name!r} is not in the Dataset and cannot be rebuilt")
    v = ds[name]
    dims = v.dims
    if dims == ("profile", "channel", "bin"):
        return v.values
    if dims == ("channel", "bin"):
        return np.broadcast_to(v.values, (p, c, b)).copy()
    if dims == ("column", "channel", "bin"):
        return _mix(ds, v)
    if dims == ("profile", "channel"):
        return np.repeat(v.values[:, :, None], b, axis=2)
    raise ValueError(f"{name!r} is {dims}: not a truth this function rebuilds per profile")


def per_profile(ds: xr.Dataset, name: str) -> xr.DataArray:
    """The (profile, channel, bin) array ``name`` of a raw file's Dataset, rebuilt from
    whatever form it holds (docs/file-format.md, "The truth of each profile"): exactly
    the values ``simulate --truth per-profile`` writes for ``expected_signal``,
    ``expected_background``, ``expected_counts``, ``snr_eq4`` and
    ``attenuated_backscatter``, and the profile's mix of its columns for every other
    (column, channel, bin) truth (``beta_cld``, ``t2``, ...). ``ds`` is what
    ``xarray.open_dataset(path, engine="h5netcdf")`` or ``simulate`` returns; select
    profiles first (``ds.isel(profile=slice(0, 1000))``) for a long run."""
    data = _as_per_profile(ds, name)
    attrs = dict(ds[name].attrs) if name in ds else {}
    attrs.pop("coordinates", None)
    coords = {"profile": ds["profile"], "channel": ds["channel"]}
    if "channel_name" in ds.coords:
        coords["channel_name"] = ds["channel_name"]
    return xr.DataArray(data, dims=("profile", "channel", "bin"),
                        coords=coords,
                        name=name, attrs=attrs)


def _whole(name: str, value: Optional[int]) -> Optional[int]:
    """An optional whole-number argument (``profiles``, ``realizations``, ``seed``) in
    the range of the CLI's option of that name, refused as ``ValueError`` with the CLI's
    range (not Python's OverflowError or TypeError) otherwise."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int):
        raise ValueError(f"{name} = {value!r}: must be a whole number (an int)")
    return _lidarsim.whole_option(name, str(value))


class _Terminated(BaseException):
    """SIGTERM received during a call: the run was stopped as Ctrl-C stops it."""


@contextlib.contextmanager
def _terminable():
    """SIGTERM handled as Ctrl-C while a call runs: the run stops and removes the file
    it was writing, then the process ends by SIGTERM as it would have. Only where
    SIGTERM has its default action and on the main thread (where Python takes signals);
    a handler of the caller's own is left as it is."""
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL):
        yield
        return

    def stop(signum, frame):
        raise _Terminated()

    signal.signal(signal.SIGTERM, stop)
    try:
        yield
    except _Terminated:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGTERM)
        raise  # not reached: SIGTERM's default action ends the process
    finally:
        if signal.getsignal(signal.SIGTERM) is stop:
            signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _warn(warning: Optional[str]) -> None:
    if warning:
        warnings.warn(warning, stacklevel=3)


def validate(config: ConfigLike, realizations: int = 1000, seed: Optional[int] = None) -> dict:
    """``lidarsim validate CONFIG --json``: draws ``realizations`` profiles and tests
    them against Eq. 4; the report (``report["consistent"]``, the statistics and every
    bin) as the CLI's JSON, parsed."""
    cfg = _config(config)
    realizations, seed = _whole("realizations", realizations), _whole("seed", seed)
    with _terminable():
        return json.loads(_lidarsim.validate(cfg.loaded, realizations, seed))


def validate_file(path: Union[str, os.PathLike]) -> dict:
    """``lidarsim validate --file RAW --json``: a raw file's counts against the
    expectation it carries; the report, parsed."""
    return json.loads(_lidarsim.validate_file(os.fspath(path)))


#: The units of a config key, from the unit its name ends in (the house rule: units in
#: names, docs/config.md); a key without a unit suffix is dimensionless ("1").
_KEY_UNITS = (("_g_per_kg", "g kg-1"), ("_j", "J"), ("_w", "W"),
              ("_hz", "Hz"), ("_mhz", "MHz"), ("_nm", "nm"), ("_um", "um"), ("_mm", "mm"),
              ("_km", "km"), ("_m", "m"), ("_m2", "m2"), ("_ns", "ns"), ("_us", "us"),
              ("_s", "s"), ("_rad", "rad"), ("_mrad", "mrad"), ("_urad", "urad"),
              ("_deg", "degree"), ("_k", "K"), ("_hpa", "hPa"), ("_pa", "Pa"),
              ("_percent", "%"), ("_mps", "m s-1"), ("_m_per_s", "m s-1"),
              ("_per_m", "m-1"), ("_per_km", "km-1"), ("_per_sr", "sr-1"), ("_sr", "sr"))


def _key_units(key: str) -> str:
    """The units of a dotted config key, from its name's suffix (longest match)."""
    leaf = key.rsplit(".", 1)[-1].lower()
    found = [(len(suffix), units) for suffix, units in _KEY_UNITS
             if leaf.endswith(suffix)]
    return max(found)[1] if found else "1"


def _metric_units(metric: str) -> str:
    """The units of a sweep metric (src/design/sweep.rs): S/N and pulse counts are
    numbers, ``max_altitude`` km, ``time_to_snr`` s, ``mean_laser_power_w`` W."""
    name = metric.split(":", 1)[0]
    return {"snr_at": "1", "max_altitude": "km", "time_to_snr": "s",
            "mean_laser_power_w": "W", "pulses_in_flight": "1"}.get(name, "1")


def _vary_values(key: Any, v: Any) -> Union[str, list]:
    """One ``vary`` entry as the module passes it: a range string as it is, a list,
    tuple or numpy array of numbers as a list of floats; anything else refused."""
    if not isinstance(key, str):
        raise ValueError(f"vary: the key {key!r} is not a dotted string "
                         '("instrument.pulse_energy_j")')
    if isinstance(v, str):
        return v
    v = _plain(v)
    if isinstance(v, (list, tuple)) and all(
            isinstance(x, (int, float)) and not isinstance(x, bool) for x in map(_plain, v)):
        return [float(_plain(x)) for x in v]
    raise ValueError(f"vary {key}: {str(v)[:60]!r} is neither a range (\"0.01..1:log:5\") "
                     "nor a list of numbers")


def sweep(config: ConfigLike, vary: Mapping[str, Any],
          metrics: Union[str, Sequence[str]], channel: Optional[str] = None) -> xr.Dataset:
    """``lidarsim sweep CONFIG --vary KEY=RANGE ... --metric M ...``: the metrics over
    the grid of the varied keys, one dimension per key (``vary`` maps a dotted key to
    its range, ``"0.01..1:log:5"``, or to a list or numpy array of values; the CLI's
    numbers). ``metrics``: one metric (a string, ``"snr_at:10km"``) or a list of them.
    ``channel``: the channel the metrics are of, required for a multi-channel config.
    Every variable carries ``units``."""
    cfg = _config(config)
    if not isinstance(vary, Mapping) or not vary:
        raise ValueError(
            f"vary = {str(vary)[:60]!r}: must be a dict of dotted keys to ranges or lists, "
            'e.g. {"instrument.pulse_energy_j": "0.01..1:log:5"}')
    axes = [(k, _vary_values(k, v)) for k, v in vary.items()]
    if isinstance(metrics, str):
        metrics = [metrics]
    elif not isinstance(metrics, Sequence) or not all(isinstance(m, str) for m in metrics):
        raise ValueError(f"metrics = {str(metrics)[:60]!r}: must be a metric (a string, "
                         '"snr_at:10km") or a list of them')
    if channel is not None and not isinstance(channel, str):
        raise ValueError(f"channel = {channel!r}: must be a channel's name (a string)")
    with _terminable():
        grid, rows = _lidarsim.sweep(cfg.loaded, axes, list(metrics), channel)
    keys = [k for k, _ in grid]
    shape = tuple(len(values) for _, values in grid)
    table = np.array([m for _, m in rows], dtype="float64").reshape(shape + (len(metrics),))
    data = {m: (keys, table[..., i], {"units": _metric_units(m)})
            for i, m in enumerate(metrics)}
    coords = {k: (k, np.array(values), {"units": _key_units(k)}) for k, values in grid}
    attrs = {"config_file": os.fspath(cfg.path)}
    if channel is not None:
        attrs["channel"] = channel
    return xr.Dataset(data, coords=coords, attrs=attrs)
