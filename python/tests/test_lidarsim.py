"""The Python module against the CLI it mirrors (docs/python.md): the same numbers to
the last bit, the same counts for the same seed, the same one-line refusals."""

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import lidarsim

ROOT = Path(__file__).resolve().parents[2]
CLI = Path(os.environ.get("LIDARSIM_BIN", ROOT / "target" / "release" / "lidarsim"))
SCENARIO1 = ROOT / "configs" / "paper" / "scenario1.toml"
CALIOP = ROOT / "configs" / "instruments" / "caliop_3ch.toml"


def cli(*args, cwd=None):
    assert CLI.exists(), f"build the CLI first (cargo build --release): {CLI}"
    return subprocess.run([str(CLI), *map(str, args)], capture_output=True, text=True, cwd=cwd)


def test_expect_equals_the_cli_csv_to_the_last_bit(tmp_path):
    cfg = lidarsim.load_config(CALIOP, {"instrument.pulse_energy_j": 0.05})
    ds = lidarsim.expect(cfg, channel="532_perpendicular")
    out = tmp_path / "e.csv"
    r = cli("expect", CALIOP, "--set", "instrument.pulse_energy_j=0.05",
            "--channel", "532_perpendicular", "--csv", out)
    assert r.returncode == 0, r.stderr
    header = out.read_text().splitlines()[0].split(",")
    table = np.genfromtxt(out, delimiter=",", skip_header=1)
    for k, name in enumerate(header):
        ours = {"altitude_m": ds.altitude, "range_m": ds.range}.get(name, ds.get(name))
        ours = np.asarray(ours)
        theirs = table[:, k]
        same = (ours == theirs) | (np.isnan(ours) & np.isnan(theirs))
        assert same.all(), f"{name}: {ours[~same][:3]} against {theirs[~same][:3]}"
    assert ds.attrs["channel"] == "532_perpendicular"
    assert ds.snr.dims == ("bin",)


def test_same_seed_same_counts_and_truth_as_the_cli(tmp_path):
    r = cli("simulate", SCENARIO1, "-o", tmp_path / "cli.nc", "--profiles", "5", "--seed", "7")
    assert r.returncode == 0, r.stderr
    written = lidarsim.simulate(SCENARIO1, profiles=5, seed=7, path=tmp_path / "py.nc")
    assert written == tmp_path / "py.nc"
    in_memory = lidarsim.simulate(SCENARIO1, profiles=5, seed=7)
    import xarray as xr

    theirs = xr.load_dataset(tmp_path / "cli.nc", engine="h5netcdf")
    for ours in (xr.load_dataset(written, engine="h5netcdf"), in_memory):
        assert ours.counts.dims == ("profile", "channel", "bin")
        for name in ("counts", "attenuated_backscatter", "expected_signal", "t2"):
            np.testing.assert_array_equal(ours[name].values, theirs[name].values, err_msg=name)
    # another seed, other counts
    other = lidarsim.simulate(SCENARIO1, profiles=5, seed=8)
    assert not np.array_equal(other.counts.values, theirs.counts.values)


def refusal(*args):
    """The CLI's one-line message, without its `lidarsim: error: ` prefix."""
    r = cli(*args)
    assert r.returncode == 2, r.stderr
    line = r.stderr.strip()
    assert len(line.splitlines()) == 1, line
    return line.removeprefix("lidarsim: error: ")


def test_bad_input_raises_the_cli_message(tmp_path):
    # a bad value: ValueError, the CLI's message
    msg = refusal("expect", SCENARIO1, "--set", "instrument.pulse_energy_j=-1")
    with pytest.raises(ValueError) as e:
        lidarsim.load_config(SCENARIO1, instrument__pulse_energy_j=-1)
    assert str(e.value) == msg
    # no such file: OSError, the CLI's message
    missing = tmp_path / "missing.toml"
    msg = refusal("expect", missing)
    with pytest.raises(OSError) as e:
        lidarsim.expect(missing)
    assert str(e.value) == msg
    # an output that is the input: refused, nothing written over it
    before = SCENARIO1.read_bytes()
    with pytest.raises(OSError):
        lidarsim.simulate(SCENARIO1, profiles=1, path=SCENARIO1)
    assert SCENARIO1.read_bytes() == before
    # a value Python cannot write as TOML
    with pytest.raises(ValueError):
        lidarsim.load_config(SCENARIO1, {"instrument.pulse_energy_j": float("nan")})


def test_validate_gives_the_cli_report(tmp_path):
    ours = lidarsim.validate(SCENARIO1, realizations=200, seed=3)
    r = cli("validate", SCENARIO1, "--realizations", "200", "--seed", "3",
            "--json", tmp_path / "v.json")
    assert r.returncode == 0, r.stderr
    import json

    theirs = json.loads((tmp_path / "v.json").read_text())
    assert ours == theirs
    assert ours["consistent"] is True
    with pytest.raises(ValueError):
        lidarsim.validate(SCENARIO1, realizations=5)


def test_validate_file_gives_the_cli_report(tmp_path):
    raw = lidarsim.simulate(SCENARIO1, profiles=200, seed=4, path=tmp_path / "r.nc")
    ours = lidarsim.validate_file(raw)
    r = cli("validate", "--file", raw, "--json", tmp_path / "v.json")
    import json

    theirs = json.loads((tmp_path / "v.json").read_text())
    assert r.returncode in (0, 1), r.stderr
    assert ours == theirs
    with pytest.raises(OSError):
        lidarsim.validate_file(tmp_path / "missing.nc")


def test_sweep_is_the_cli_csv_on_a_grid(tmp_path):
    vary = {"instrument.pulse_energy_j": "0.01..1:log:3", "instrument.rep_rate_hz": "10..30:3"}
    ds = lidarsim.sweep(SCENARIO1, vary, ["snr_at:11km", "max_altitude:snr=3"])
    assert ds["snr_at:11km"].dims == tuple(vary)
    assert ds["snr_at:11km"].shape == (3, 3)
    out = tmp_path / "s.csv"
    args = [a for k, v in vary.items() for a in ("--vary", f"{k}={v}")]
    r = cli("sweep", SCENARIO1, *args, "--metric", "snr_at:11km",
            "--metric", "max_altitude:snr=3", "--csv", out)
    assert r.returncode == 0, r.stderr
    table = np.genfromtxt(out, delimiter=",", skip_header=1)
    np.testing.assert_array_equal(ds["snr_at:11km"].values.ravel(), table[:, 2])
    # the S/N grows with the energy and the rate
    snr = ds["snr_at:11km"].values
    assert (np.diff(snr, axis=0) > 0).all() and (np.diff(snr, axis=1) > 0).all()
