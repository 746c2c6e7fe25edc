"""The Python module's overhead against the CLI (docs/python.md, "Speed").

Run from the repository root, with the module installed and the CLI built
(``cargo build --release``)::

    python python/benchmarks/overhead.py

Prints, for the CALIOP-like config (configs/instruments/caliop_532.toml, 3,358 bins):
``expect`` per call on a loaded Config and from a path (load included), and an
in-memory ``simulate`` of 10,000 aggregate profiles against the CLI writing the same
run (its whole time and its drawing time, from its summary line). Medians of repeats.
"""

import re
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import lidarsim

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "configs" / "instruments" / "caliop_532.toml"
CLI = ROOT / "target" / "release" / "lidarsim"
PROFILES = 10_000


def per_call_ms(call, repeats=200):
    call()
    start = time.perf_counter()
    for _ in range(repeats):
        call()
    return (time.perf_counter() - start) / repeats * 1e3


def cli_run_s(seed):
    """The CLI's whole time and drawing time for the run, from its summary line."""
    with tempfile.TemporaryDirectory() as d:
        r = subprocess.run([str(CLI), "simulate", str(CONFIG), "-o", f"{d}/raw.nc",
                            "--profiles", str(PROFILES), "--method", "aggregate",
                            "--seed", str(seed)], capture_output=True, text=True, check=True)
    m = re.search(r"([0-9.]+) s in all .* drawing ([0-9.]+) s", r.stderr)
    return float(m.group(1)), float(m.group(2))


def main():
    cfg = lidarsim.load_config(CONFIG)
    print(f"expect, loaded Config: {per_call_ms(lambda: lidarsim.expect(cfg)):.2f} ms a call")
    print(f"expect, from a path:   "
          f"{per_call_ms(lambda: lidarsim.expect(CONFIG), 50):.2f} ms a call")
    ours, whole, drawing = [], [], []
    for seed in range(1, 16):
        start = time.perf_counter()
        lidarsim.simulate(cfg, profiles=PROFILES, seed=seed, method="aggregate")
        ours.append(time.perf_counter() - start)
        w, d = cli_run_s(seed)
        whole.append(w)
        drawing.append(d)
    ours, whole, drawing = (statistics.median(x) for x in (ours, whole, drawing))
    print(f"simulate {PROFILES} aggregate profiles in memory: {ours:.3f} s; the CLI "
          f"{whole:.3f} s in all, drawing {drawing:.3f} s "
          f"({ours / drawing:.2f}x its drawing, {ours / whole:.2f}x its whole run)")


if __name__ == "__main__":
    main()
