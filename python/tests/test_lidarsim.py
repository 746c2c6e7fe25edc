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


# the CSV's columns in expect's Dataset: the raw file's names (the point truth of the
# scene's one column)
CSV_IN_DATASET = {"altitude_m": "altitude", "range_m": "range", "signal": "expected_signal",
                  "background": "expected_background", "dark": "expected_dark"}
# root attributes that name the moment and the call, not the run
OF_THE_CALL = ("history", "date_created")


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
        ours = ds[CSV_IN_DATASET.get(name, name)]
        ours = np.asarray(ours.isel(column=0) if "column" in ours.dims else ours)
        theirs = table[:, k]
        same = (ours == theirs) | (np.isnan(ours) & np.isnan(theirs))
        assert same.all(), f"{name}: {ours[~same][:3]} against {theirs[~same][:3]}"
    assert ds.channel_name.item() == "532_perpendicular"
    assert ds.snr.dims == ("bin",)
    # the file's S/N takes the profile's whole shots (15), the CSV's rep_rate x time
    # (20.16 Hz x 0.744 s = 14.999): Eq. 4 grows as the root of the shots
    csv_shots = ds.attrs["shots_per_profile"]
    assert csv_shots == 20.16 * 0.744
    np.testing.assert_allclose(ds.snr_eq4, ds.snr * np.sqrt(15 / csv_shots), rtol=1e-12)
    with pytest.raises(ValueError, match="has no channel `1064`"):
        lidarsim.expect(cfg, channel="1064")


def test_expect_is_the_raw_file_before_its_first_profile(tmp_path):
    """Every channel, the raw file's variables that do not depend on the profile, with
    the file's values, dimensions and attributes."""
    import xarray as xr

    model = lidarsim.expect(CALIOP)
    r = cli("simulate", CALIOP, "-o", tmp_path / "cli.nc", "--profiles", "2")
    assert r.returncode == 0, r.stderr
    raw = xr.load_dataset(tmp_path / "cli.nc", engine="h5netcdf")
    assert list(model.channel.values) == list(raw.channel.values)
    fixed = [n for n in raw.variables if "profile" not in raw[n].dims]
    assert set(model.variables) - {"snr", "snr_bkg_estimated"} == set(fixed)
    for name in fixed:  # (channel_name is an index in memory: compare the plain values)
        xr.testing.assert_identical(model[name].variable.to_base_variable(),
                                    raw[name].variable.to_base_variable())
    assert model.snr_bkg_estimated.dims == ("channel", "bin")


def test_expect_of_a_changing_scene_is_its_first_column(tmp_path):
    """An orbit's file holds its expectations per profile; expect gives the first
    column's, per channel and bin: the CLI's CSV."""
    orbit = ROOT / "configs" / "instruments" / "caliop_orbit.toml"
    model = lidarsim.expect(orbit)
    r = cli("expect", orbit, "--csv", tmp_path / "e.csv")
    assert r.returncode == 0, r.stderr
    table = np.genfromtxt(tmp_path / "e.csv", delimiter=",", skip_header=1)
    assert model.expected_signal.dims == ("channel", "bin")
    np.testing.assert_array_equal(model.expected_signal.isel(channel=0), table[:, 7])
    np.testing.assert_array_equal(model.snr.isel(channel=0), table[:, 10])
    assert "profile" not in model.dims


def memory_owner(a):
    """The object at the end of an array's chain of bases."""
    while getattr(a, "base", None) is not None:
        a = a.base
    return a


def by_name(ds):
    """A Dataset read from a file as the module returns it: the channels indexed by
    ``channel_name`` (docs/python.md), the one difference."""
    return ds if "channel_name" in ds.xindexes else ds.set_xindex("channel_name")


def test_same_seed_same_counts_and_truth_as_the_cli(tmp_path):
    import xarray as xr

    r = cli("simulate", SCENARIO1, "-o", tmp_path / "cli.nc", "--profiles", "5", "--seed", "7")
    assert r.returncode == 0, r.stderr
    written = lidarsim.simulate(SCENARIO1, profiles=5, seed=7, path=tmp_path / "py.nc")
    assert written == tmp_path / "py.nc"
    in_memory = lidarsim.simulate(SCENARIO1, profiles=5, seed=7)
    theirs = by_name(xr.load_dataset(tmp_path / "cli.nc", engine="h5netcdf"))
    for ours in (by_name(xr.load_dataset(written, engine="h5netcdf")), in_memory):
        for a in OF_THE_CALL:
            ours.attrs[a] = theirs.attrs[a]
        # every variable, dimension, coordinate and attribute, every value
        xr.testing.assert_identical(ours, theirs)
    assert in_memory.counts.dtype == theirs.counts.dtype == np.uint32  # the file's width
    # the counts are the run's own buffer, handed to numpy without a copy
    assert type(memory_owner(in_memory.counts.values)).__name__ == "PySliceContainer"
    # a progress bar asked for (hidden: standard error is no terminal here) changes nothing
    shown = lidarsim.simulate(SCENARIO1, profiles=5, seed=7, progress=True)
    np.testing.assert_array_equal(shown.counts.values, theirs.counts.values)
    # another seed, other counts
    other = lidarsim.simulate(SCENARIO1, profiles=5, seed=8)
    assert not np.array_equal(other.counts.values, theirs.counts.values)


def test_a_changing_scene_in_memory_is_the_file(tmp_path):
    """An orbit (geolocation, columns, per-profile truth): in memory as in the file."""
    import xarray as xr

    orbit = ROOT / "configs" / "instruments" / "caliop_orbit.toml"
    r = cli("simulate", orbit, "-o", tmp_path / "cli.nc", "--profiles", "30", "--seed", "2",
            "--method", "aggregate")
    assert r.returncode == 0, r.stderr
    ours = lidarsim.simulate(orbit, profiles=30, seed=2, method="aggregate")
    theirs = by_name(xr.load_dataset(tmp_path / "cli.nc", engine="h5netcdf"))
    for a in OF_THE_CALL:
        ours.attrs[a] = theirs.attrs[a]
    xr.testing.assert_identical(ours, theirs)
    assert "latitude" in ours.counts.coords
    with pytest.raises(ValueError, match="method `fast` is not one of auto, shot, aggregate"):
        lidarsim.simulate(orbit, profiles=3, method="fast")



def test_per_profile_is_what_truth_per_profile_writes(tmp_path):
    """The orbit's compact truth (format 4: per column, the sky per (profile, channel),
    no expected_counts or snr_eq4 of its ideal detector) rebuilt by per_profile: every
    value, to the bit, what `simulate --truth per-profile` writes; the in-memory run
    takes the same argument."""
    import xarray as xr

    orbit = ROOT / "configs" / "instruments" / "caliop_orbit.toml"
    args = ["--profiles", "30", "--seed", "2", "--method", "aggregate"]
    for truth in ("compact", "per-profile"):
        r = cli("simulate", orbit, "-o", tmp_path / f"{truth}.nc", *args, "--truth", truth)
        assert r.returncode == 0, r.stderr
    compact = xr.load_dataset(tmp_path / "compact.nc", engine="h5netcdf")
    full = xr.load_dataset(tmp_path / "per-profile.nc", engine="h5netcdf")
    assert compact.expected_signal.dims == ("column", "channel", "bin")
    assert compact.expected_background.dims == ("profile", "channel")
    assert "expected_counts" not in compact and "snr_eq4" not in compact
    for name in lidarsim.PER_PROFILE_NAMES:
        rebuilt = lidarsim.per_profile(compact, name)
        assert rebuilt.dims == full[name].dims == ("profile", "channel", "bin"), name
        np.testing.assert_array_equal(rebuilt.values.view(np.uint64),
                                      full[name].values.view(np.uint64), err_msg=name)
    in_memory = lidarsim.simulate(orbit, profiles=30, seed=2, method="aggregate",
                                  truth="per-profile")
    np.testing.assert_array_equal(in_memory.snr_eq4.values, full.snr_eq4.values)
    with pytest.raises(ValueError, match="truth `full` is not one of compact, per-profile"):
        lidarsim.simulate(orbit, profiles=3, truth="full")


INTERRUPTED_RUN = """
import sys, time, lidarsim
what, path = sys.argv[2], (sys.argv[3] if len(sys.argv) > 3 else None)
print("started", flush=True)
try:
    if what == "validate":
        lidarsim.validate(sys.argv[1], realizations=4_000_000, seed=1)
    elif what == "validate_slow":  # realizations of seconds each (MPL-like: 150,000 shots)
        lidarsim.validate(sys.argv[1], realizations=1000, seed=1)
    elif what == "sweep":
        lidarsim.sweep(sys.argv[1], {"instrument.pulse_energy_j": "0.01..1:1000000"},
                       ["snr_at:11km"])
    else:
        lidarsim.simulate(sys.argv[1], profiles=400_000, seed=1, method="shot", path=path)
except KeyboardInterrupt:
    print("KeyboardInterrupt", time.monotonic(), flush=True)
    sys.exit(3)
"""


MPL = ROOT / "configs" / "ground" / "mpl_like.toml"


@pytest.mark.parametrize("call", ["simulate to a file", "simulate", "validate", "sweep",
                                  "validate_slow"])
def test_ctrl_c_stops_a_long_run_within_a_second_and_leaves_no_file(tmp_path, call):
    import signal
    import sys
    import time

    out = tmp_path / "out"
    out.mkdir()
    config = MPL if call == "validate_slow" else SCENARIO1
    args = [sys.executable, "-c", INTERRUPTED_RUN, str(config), call.split()[0]]
    if call.endswith("file"):
        args.append(str(out / "raw.nc"))
    p = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "started"
    # well into the run (each takes over 10 s; MPL-like's model takes ~1 s before its
    # first realization)
    time.sleep(4.0 if call == "validate_slow" else 1.5)
    assert p.poll() is None, p.stderr.read()
    sent = time.monotonic()
    p.send_signal(signal.SIGINT)
    stdout, stderr = p.communicate(timeout=30)
    assert p.returncode == 3, stderr
    caught = float(stdout.split()[-1])
    assert caught - sent < 1.0, f"{caught - sent:.2f} s"
    assert list(out.iterdir()) == []


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
    # whole numbers out of range or of another type: ValueError, not Python's own
    # OverflowError or TypeError; out of range, the CLI's range for its option
    for option, bad in (("profiles", -1), ("profiles", 0), ("profiles", 2**64),
                        ("realizations", -1), ("realizations", 10**9), ("seed", -3)):
        command = ("validate",) if option == "realizations" else ("simulate", "-o",
                                                                     tmp_path / "x.nc")
        reason = refusal(command[0], SCENARIO1, *command[1:], f"--{option}", str(bad))
        # clap's: "invalid value ... '--OPT': WHY (see lidarsim --help)"
        reason = reason.split("': ", 1)[1].removesuffix(" (see lidarsim --help)")
        call = lidarsim.validate if option == "realizations" else lidarsim.simulate
        with pytest.raises(ValueError) as e:
            call(SCENARIO1, **{option: bad})
        assert str(e.value) == f"{option} = {bad}: {reason}"
    for bad in (2.5, True, "3"):
        with pytest.raises(ValueError, match="must be a whole number"):
            lidarsim.simulate(SCENARIO1, profiles=bad)
    # an in-memory run larger than the memory: refused before anything is allocated
    with pytest.raises(ValueError, match="in memory needs about .* of memory"):
        lidarsim.simulate(SCENARIO1, profiles=10**9)


def test_validate_gives_the_cli_report(tmp_path):
    # 700 realizations: drawn in three blocks (to look for Ctrl-C between them), the
    # CLI's in one; the sums add exactly, so the reports are equal
    ours = lidarsim.validate(SCENARIO1, realizations=700, seed=3)
    r = cli("validate", SCENARIO1, "--realizations", "700", "--seed", "3",
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


def test_the_dataset_is_decoded_as_xarray_decodes_a_file():
    """_dataset's shortcuts (time, NaN fill values, coordinates) give what xarray's own
    CF decoding gives, also when a later variable needs the whole decoding."""
    import xarray as xr

    s = ("str",)
    variables = [
        ("bin", ("bin",), np.arange(3), []),
        ("altitude", ("bin",), np.arange(3.0), [("units", s + ("m",))]),
        ("time", ("bin",), np.array([0.5, 1.5, 2.5]),
         [("units", s + ("seconds since 2000-01-01 00:00:00",)), ("calendar", s + ("standard",))]),
        ("a", ("bin",), np.array([1.0, np.nan, 2.0]),
         [("_FillValue", ("f64", float("nan"))), ("coordinates", s + ("time altitude",))]),
        ("b", ("bin",), np.array([1, 2, -9], dtype=np.int32),
         [("_FillValue", ("i32", -9)), ("coordinates", s + ("altitude",))]),
    ]
    ours = lidarsim._dataset(variables, [("title", s + ("t",))])
    attrs = lambda items: {k: lidarsim._ATTR_TYPES[t](v) for k, (t, v) in items}
    raw = xr.Dataset({n: xr.Variable(d, v, attrs=attrs(a)) for n, d, v, a in variables},
                     attrs={"title": "t"})
    xr.testing.assert_identical(ours, xr.decode_cf(raw))
    assert np.isnan(ours.b.values[2]) and ours.time.dtype.kind == "M"


def test_sigterm_stops_a_run_to_a_file_and_leaves_nothing(tmp_path):
    """SIGTERM (a batch system's stop) during ``simulate(path=...)``: the run stops as
    Ctrl-C stops it, its temporary and lock files removed, and the process ends by
    SIGTERM as it would have."""
    import signal
    import sys
    import time

    out = tmp_path / "out"
    out.mkdir()
    args = [sys.executable, "-c", INTERRUPTED_RUN, str(SCENARIO1), "simulate",
            str(out / "raw.nc")]
    p = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "started"
    time.sleep(1.5)
    assert p.poll() is None, p.stderr.read()
    assert list(out.iterdir()) != []  # the run's temporary file (and lock) exist
    sent = time.monotonic()
    p.send_signal(signal.SIGTERM)
    _, stderr = p.communicate(timeout=30)
    assert time.monotonic() - sent < 2.0
    assert p.returncode == -signal.SIGTERM, stderr
    assert list(out.iterdir()) == []


def test_a_long_run_is_announced_as_a_warning_not_printed():
    """The library's duration notice ("expected to take about ...") is a UserWarning;
    nothing is printed on stderr (docs/python.md). As an error (``-W error``) it stops
    the run at once."""
    import sys

    script = (
        "import warnings, lidarsim\n"
        "warnings.simplefilter('error')\n"
        "try:\n"
        f"    lidarsim.validate({str(SCENARIO1)!r}, realizations=100_000_000, seed=1)\n"
        "except UserWarning as w:\n"
        "    print('warned:', w)\n")
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("warned: lidarsim: validating 100000000 realizations"), r.stdout
    assert "expected to take about" in r.stdout
    assert r.stderr == ""


def test_sweep_takes_one_metric_as_a_string_and_refuses_a_bad_vary():
    vary = {"instrument.pulse_energy_j": "0.01..1:log:3"}
    one = lidarsim.sweep(SCENARIO1, vary, "snr_at:11km")
    assert list(one.data_vars) == ["snr_at:11km"]
    listed = lidarsim.sweep(SCENARIO1, vary, ["snr_at:11km"])
    np.testing.assert_array_equal(one["snr_at:11km"], listed["snr_at:11km"])
    for bad in ("instrument.pulse_energy_j=0.01..1:3", ["instrument.pulse_energy_j"], {},
                {"instrument.pulse_energy_j": 3}, {"instrument.pulse_energy_j": ["a"]},
                {"instrument.pulse_energy_j": []}):
        with pytest.raises(ValueError, match="vary"):
            lidarsim.sweep(SCENARIO1, bad, "snr_at:11km")
    with pytest.raises(ValueError, match="metrics"):
        lidarsim.sweep(SCENARIO1, vary, [3])


# the CALIOP-like config's 532 nm perpendicular channel alone, as the CLI's --set writes it
PERPENDICULAR = {"name": "532_perpendicular", "polarization": "perpendicular",
                 "crosstalk": 0.005}
PERPENDICULAR_SET = ('instrument.channels=[{name = "532_perpendicular", '
                     'polarization = "perpendicular", crosstalk = 0.005}]')


def test_numpy_scalars_and_arrays_are_overrides():
    cfg = lidarsim.Config(SCENARIO1, {"instrument.pulse_energy_j": np.float64(0.1),
                                      "instrument.rep_rate_hz": np.int64(20),
                                      "atmosphere.layers.0.top_km": np.float32(12.5)})
    assert cfg.sets() == ["instrument.pulse_energy_j=0.1", "instrument.rep_rate_hz=20",
                          "atmosphere.layers.0.top_km=12.5"]
    plain = lidarsim.expect(lidarsim.load_config(SCENARIO1, {"instrument.pulse_energy_j": 0.1}))
    np.testing.assert_array_equal(lidarsim.expect(lidarsim.load_config(
        SCENARIO1, {"instrument.pulse_energy_j": np.float64(0.1)}))["expected_signal"],
        plain["expected_signal"])
    arr = lidarsim.Config(SCENARIO1, {"a.b": np.array([1.0, 2.5]), "a.c": np.bool_(True)})
    assert arr.sets() == ["a.b=[1.0, 2.5]", "a.c=true"]


def test_dicts_are_tables_and_nested_dicts_are_merged_key_by_key(tmp_path):
    cfg = lidarsim.Config(SCENARIO1, {"atmosphere": {"water_vapour": {
        "altitude_km": np.array([0.0, 10.0]), "mixing_ratio_g_per_kg": [8, 0.01]}},
        "instrument.channels": [PERPENDICULAR]})
    assert cfg.sets() == [
        "atmosphere.water_vapour.altitude_km=[0.0, 10.0]",
        "atmosphere.water_vapour.mixing_ratio_g_per_kg=[8, 0.01]",
        'instrument.channels=[{name = "532_perpendicular", polarization = "perpendicular", '
        'crosstalk = 0.005}]']
    # a layer list replaces the config's: the CLI's --set of the same TOML, to the bit
    layer = {"kind": "cloud", "base_km": 2.0, "top_km": np.float64(3.5),
             "extinction_per_km": 0.5, "lidar_ratio_sr": 20, "multiple_scattering": 1.0}
    layers = lidarsim.Config(SCENARIO1, {"atmosphere.layers": [layer]})
    (item,) = layers.sets()
    ds = lidarsim.expect(layers)
    out = tmp_path / "layers.csv"
    r = cli("expect", SCENARIO1, "--set", item, "--csv", out)
    assert r.returncode == 0, r.stderr
    table = np.genfromtxt(out, delimiter=",", names=True)
    np.testing.assert_array_equal(ds["expected_signal"].values.ravel(), table["signal"])


def test_an_override_that_is_no_toml_value_is_one_line_naming_the_key():
    for bad in (object(), {1: 2}, float("nan"), np.float64("inf"), {"x": {3: 1}}):
        with pytest.raises(ValueError, match=r"--set instrument\.pulse_energy_j") as e:
            lidarsim.Config(SCENARIO1, {"instrument.pulse_energy_j": bad}).sets()
        assert "\n" not in str(e.value) and "object at 0x" not in str(e.value)


def test_version_is_the_crates():
    import re
    text = (ROOT / "Cargo.toml").read_text()
    version = re.search(r'^version = "([^"]+)"', text, re.M).group(1)
    assert lidarsim.__version__ == version
    assert cli("--version").stdout.split()[-1] == version


def test_sweep_of_a_channel_equals_the_cli_expect_of_that_channel(tmp_path):
    """Each value of the list against ``lidarsim expect --channel C --csv`` with that
    value: ``snr_at:Zkm`` is the CSV's ``snr`` (Eq. 4, M = rate x accumulation time) at
    the bin nearest Z, ``max_altitude:snr=X`` the highest altitude with ``snr`` >= X."""
    energies = [0.02, 0.11, 0.3]
    metrics = ["snr_at:10km", "max_altitude:snr=1"]
    ds = lidarsim.sweep(CALIOP, {"instrument.pulse_energy_j": np.array(energies)}, metrics,
                        channel="532_perpendicular")
    out = tmp_path / "e.csv"
    for i, e in enumerate(energies):
        r = cli("expect", CALIOP, "--set", f"instrument.pulse_energy_j={e}",
                "--channel", "532_perpendicular", "--csv", out)
        assert r.returncode == 0, r.stderr
        t = np.genfromtxt(out, delimiter=",", names=True)
        assert ds[metrics[0]].values[i] == t["snr"][np.argmin(abs(t["altitude_m"] - 10e3))]
        assert ds[metrics[1]].values[i] == pytest.approx(
            t["altitude_m"][t["snr"] >= 1].max() / 1e3, rel=1e-12)
    assert ds[metrics[0]].attrs["units"] == "1" and ds[metrics[1]].attrs["units"] == "km"
    assert ds["instrument.pulse_energy_j"].attrs["units"] == "J"
    np.testing.assert_array_equal(ds["instrument.pulse_energy_j"], energies)
    assert ds.attrs["channel"] == "532_perpendicular"


def test_a_multi_channel_sweep_asks_for_a_channel_in_one_line():
    vary = {"instrument.pulse_energy_j": np.array([0.05, 0.1])}
    with pytest.raises(ValueError, match="pass channel= one of 532_parallel") as e:
        lidarsim.sweep(CALIOP, vary, "snr_at:10km")
    assert "Scenario" not in str(e.value) and "\n" not in str(e.value)
    with pytest.raises(ValueError, match="has no channel `355`"):
        lidarsim.sweep(CALIOP, vary, "snr_at:10km", channel="355")
    both = [lidarsim.sweep(CALIOP, vary, "snr_at:10km", channel=c)["snr_at:10km"].values
            for c in ("532_parallel", "1064_total")]
    assert not np.array_equal(*both)


def test_photons_are_the_cli_photon_file_byte_for_byte(tmp_path):
    """``simulate(..., path=, photons=)`` writes the CLI's raw and photon files, byte for
    byte (same seed, same moment: ``SOURCE_DATE_EPOCH``); without ``path`` it is refused in
    one line."""
    icesat2 = ROOT / "configs" / "instruments" / "icesat2_like.toml"
    env = dict(os.environ, SOURCE_DATE_EPOCH="1733000000")
    r = subprocess.run([str(CLI), "simulate", str(icesat2), "-o", "cli.h5", "--profiles", "3",
                        "--photons", "cli_ph.h5"], capture_output=True, text=True,
                       cwd=tmp_path, env=env)
    assert r.returncode == 0, r.stderr
    os.environ["SOURCE_DATE_EPOCH"] = "1733000000"
    try:
        lidarsim.simulate(icesat2, profiles=3, path=tmp_path / "py.h5",
                          photons=tmp_path / "py_ph.h5")
    finally:
        del os.environ["SOURCE_DATE_EPOCH"]
    assert (tmp_path / "py_ph.h5").read_bytes() == (tmp_path / "cli_ph.h5").read_bytes()
    import h5py
    with h5py.File(tmp_path / "py.h5") as raw, h5py.File(tmp_path / "py_ph.h5") as ph:
        assert int(raw["counts"][()].sum()) == ph["heights/ph_id_pulse"].size > 0
    with pytest.raises(ValueError, match="give path="):
        lidarsim.simulate(icesat2, profiles=3, photons=tmp_path / "x.h5")
