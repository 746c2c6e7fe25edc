"""lidarsim in Python: the simulator's commands in the same process, their results as
xarray Datasets (docs/python.md).

    import lidarsim
    cfg = lidarsim.load_config("configs/paper/scenario1.toml",
                               {"instrument.pulse_energy_j": 0.5})
    model = lidarsim.expect(cfg)                  # per bin: signal, background, S/N, ...
    raw = lidarsim.simulate(cfg, profiles=100, seed=1)   # the raw file's Dataset

Bad input raises ``ValueError`` (files: ``OSError``) with the one-line message the CLI
prints. Long calls release the GIL.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Optional, Union

import xarray as xr

from . import _lidarsim

__all__ = ["Config", "load_config", "expect", "simulate", "validate", "validate_file", "sweep"]


def _toml_value(key: str, value: Any) -> str:
    """A Python value as the TOML of a ``--set KEY=VALUE`` override."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"--set {key}: {value} is not a finite number")
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)  # a TOML basic string
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(key, v) for v in value) + "]"
    raise ValueError(f"--set {key}: a {type(value).__name__} is not a TOML value")


@dataclass(frozen=True)
class Config:
    """A scenario config file and dotted-key overrides, checked when made."""

    path: Path
    overrides: Mapping[str, Any] = field(default_factory=dict)

    def sets(self) -> list:
        """The overrides as the CLI's ``--set KEY=VALUE`` arguments."""
        return [f"{k}={_toml_value(k, v)}" for k, v in self.overrides.items()]

    @property
    def channels(self) -> list:
        """The receiver channels' names."""
        return _lidarsim.check(os.fspath(self.path), self.sets())


ConfigLike = Union[Config, str, os.PathLike]


def load_config(path: Union[str, os.PathLike], overrides: Optional[Mapping[str, Any]] = None,
                **keys: Any) -> Config:
    """Loads and checks a config: ``overrides`` maps dotted keys to values
    (``{"instrument.pulse_energy_j": 0.01}``); keyword arguments may spell the dots as
    double underscores (``instrument__pulse_energy_j=0.01``)."""
    o = dict(overrides or {})
    o.update({k.replace("__", "."): v for k, v in keys.items()})
    cfg = Config(Path(path), o)
    _ = cfg.channels  # raises as the CLI refuses
    return cfg


def _config(config: ConfigLike) -> Config:
    return config if isinstance(config, Config) else Config(Path(config))


def expect(config: ConfigLike, channel: Optional[str] = None) -> xr.Dataset:
    """``lidarsim expect CONFIG --csv``: the deterministic model of one channel (default
    the first) per bin, the CSV's numbers to the last bit. Dimension ``bin``; altitude
    and range are coordinates; counts per shot per bin; ``snr`` is Eq. 4 for one
    profile (``shots_per_profile`` shots)."""
    cfg = _config(config)
    cols = _lidarsim.expect(os.fspath(cfg.path), cfg.sets(), channel)
    shots = cols.pop("shots_per_profile")
    units = {"altitude_m": "m", "range_m": "m", "beta_mol": "m-1 sr-1", "beta_aer": "m-1 sr-1",
             "beta_cld": "m-1 sr-1", "alpha_total": "m-1", "t2": "1", "signal": "count",
             "background": "count", "dark": "count", "snr": "1", "snr_bkg_estimated": "1"}
    coords = {"altitude": ("bin", cols.pop("altitude_m"), {"units": "m"}),
              "range": ("bin", cols.pop("range_m"), {"units": "m"})}
    data = {k: ("bin", v, {"units": units[k]}) for k, v in cols.items()}
    return xr.Dataset(data, coords=coords, attrs={
        "config_file": os.fspath(cfg.path),
        "channel": channel or cfg.channels[0],
        "shots_per_profile": shots,
    })


def simulate(config: ConfigLike, profiles: Optional[int] = None, seed: Optional[int] = None,
             path: Union[str, os.PathLike, None] = None) -> Union[xr.Dataset, Path]:
    """``lidarsim simulate CONFIG -o PATH``: with ``path``, writes the raw file exactly
    as the CLI does (same seed, same counts and truth) and returns its path; without,
    returns the raw file's Dataset in memory (written to a temporary file and read
    back; the file is removed)."""
    cfg = _config(config)
    if path is not None:
        return Path(_lidarsim.simulate(os.fspath(cfg.path), cfg.sets(), os.fspath(path),
                                       profiles, seed))
    with tempfile.TemporaryDirectory(prefix="lidarsim-") as d:
        out = os.path.join(d, "raw.nc")
        _lidarsim.simulate(os.fspath(cfg.path), cfg.sets(), out, profiles, seed)
        return xr.load_dataset(out, engine="h5netcdf")


def validate(config: ConfigLike, realizations: int = 1000, seed: Optional[int] = None) -> dict:
    """``lidarsim validate CONFIG --json``: draws ``realizations`` profiles and tests
    them against Eq. 4; the report (``report["consistent"]``, the statistics and every
    bin) as the CLI's JSON, parsed."""
    cfg = _config(config)
    return json.loads(_lidarsim.validate(os.fspath(cfg.path), cfg.sets(), realizations, seed))


def validate_file(path: Union[str, os.PathLike]) -> dict:
    """``lidarsim validate --file RAW --json``: a raw file's counts against the
    expectation it carries; the report, parsed."""
    return json.loads(_lidarsim.validate_file(os.fspath(path)))


def sweep(config: ConfigLike, vary: Mapping[str, str], metrics: list) -> xr.Dataset:
    """``lidarsim sweep CONFIG --vary KEY=RANGE ... --metric M ...``: the metrics over
    the grid of the varied keys, one dimension per key (``vary`` maps a dotted key to
    its range, ``"0.01..1:log:5"``; the CLI's numbers, read from its CSV)."""
    import numpy as np

    cfg = _config(config)
    with tempfile.TemporaryDirectory(prefix="lidarsim-") as d:
        out = os.path.join(d, "sweep.csv")
        _lidarsim.sweep(os.fspath(cfg.path), cfg.sets(),
                        [f"{k}={v}" for k, v in vary.items()], list(metrics), out)
        with open(out) as f:
            header = f.readline().strip().split(",")
        table = np.atleast_2d(np.genfromtxt(out, delimiter=",", skip_header=1))
    keys = list(vary)
    axes = [list(dict.fromkeys(table[:, k])) for k in range(len(keys))]
    shape = tuple(len(a) for a in axes)
    data = {name: (keys, table[:, len(keys) + m].reshape(shape))
            for m, name in enumerate(header[len(keys):])}
    return xr.Dataset(data, coords={k: a for k, a in zip(keys, axes)},
                      attrs={"config_file": os.fspath(cfg.path)})
