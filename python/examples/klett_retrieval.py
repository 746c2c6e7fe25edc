"""A Klett retrieval with ``lidar_processing`` on ``lidarsim.simulate``'s Dataset,
scored against the truth the same Dataset carries (docs/python.md).

What a user of a real ground lidar does, step by step, on simulated counts:

1. simulate an hour of night-time profiles of the PollyXT-like Raman lidar and take its
   532 nm elastic channel (``532_total``);
2. average the profiles, and subtract the background measured in the pre-trigger bins
   (recorded before the laser fires: sky background and dark counts only);
3. range-correct with the bin-centre range squared, take the ozone absorption out (as
   from an ozone sounding or climatology), and average 8 bins of 7.49 m into 60 m;
4. find the reference: the middle of a clean 5.5-8.5 km region, fitted over all of it;
5. run ``lidar_processing.elastic_retrievals.klett_backscatter_aerosol`` (Klett/Fernald,
   backward from a reference in the clean free troposphere) with the molecular
   backscatter and the aerosol lidar ratio that a user takes from a sounding and from a
   Raman channel or a climatology: here the file's truth (``beta_mol``,
   ``molecular_lidar_ratio``, ``lidar_ratio_aer``, ``alpha_o3``);
6. score the retrieved aerosol backscatter against the file's ``beta_aer`` inside the
   two aerosol layers.

Why this config: the Klett solution needs a reference height where the aerosol
backscatter is known (here: zero). The shipped Elterman background aerosol of most
configs (``[atmosphere.aerosol]``, docs/model.md) leaves no aerosol-free height below
~40 km: a Klett that assumes a clean reference there comes out 6-9 % off.
``configs/ground/pollyxt_like.toml`` has no background aerosol: a boundary layer
(0.3-1.8 km, 55 sr), a lofted smoke layer (3.0-4.5 km, 70 sr) and a thin cirrus
(9-10 km), so the free troposphere between 4.5 and 9 km is clean. It also has 256
pre-trigger bins for the background (its 20 km window has no signal-free bin) and no
detector dead time, so nothing but the background stands between the counts and the
retrieval. It is used as shipped (no overrides).

Run from the repository root::

    pip install lidar_processing "scipy<1.14"
    python python/examples/klett_retrieval.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr
from lidar_processing.elastic_retrievals import klett_backscatter_aerosol

import lidarsim

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "configs" / "ground" / "pollyxt_like.toml"
CHANNEL = "532_total"
PROFILES = 12           # 12 profiles of 5 min: one hour of night-time measurement
SEED = 2026
BLOCK = 8               # 8 bins of 7.49 m averaged into ~60 m
REFERENCE = (5.5e3, 8.5e3)   # m: the clean free troposphere between the smoke and the cirrus
# Scored: the aerosol layers' interiors, one 60 m bin inside their edges (a layer edge
# cuts a bin; the retrieval and the bin-centre truth differ there by construction).
LAYERS = {"boundary layer": (0.36e3, 1.74e3), "smoke": (3.06e3, 4.44e3)}


def simulate(profiles: int = PROFILES, seed: int = SEED) -> xr.Dataset:
    """The raw file's Dataset of the PollyXT-like lidar, every channel."""
    return lidarsim.simulate(lidarsim.load_config(CONFIG), profiles=profiles, seed=seed)


def _blocks(x: np.ndarray, n: int = BLOCK) -> np.ndarray:
    """Means over consecutive blocks of n bins (a trailing partial block is dropped)."""
    m = x.size // n
    return x[: m * n].reshape(m, n).mean(axis=1)


def retrieve(raw: xr.Dataset, channel: str = CHANNEL, lidar_ratio_scale: float = 1.0,
             reference_scattering_ratio: float = 1.0) -> xr.Dataset:
    """Klett/Fernald aerosol backscatter of one channel, beside the truth, on 60 m bins.

    ``lidar_ratio_scale`` multiplies the aerosol lidar ratio handed to the retrieval,
    ``reference_scattering_ratio`` is the assumed (β_aer + β_mol)/β_mol at the
    reference: 1 and 1 are the right values, anything else a deliberate error."""
    ch = raw.sel(channel_name=channel)  # the channels by name (format 5 numbers them)
    truth = ch.isel(column=0)  # a static scene has one column of truth

    # Counts per shot, averaged over the profiles. The counts are unsigned: convert
    # before any subtraction (uint16 would wrap around).
    signal = ch.counts.astype("float64").sum("profile").values / float(raw.n_shots.sum())

    # Background: the pre-trigger bins, recorded before the pulse leaves, hold the sky
    # background and the dark counts only: their mean is every bin's background.
    n_pre = int(raw.attrs["pretrigger_bins"])
    signal = signal - signal[:n_pre].mean()

    # From here on, only the bins after the pulse (range > 0).
    keep = slice(n_pre, None)
    r = raw["range"].values[keep]
    range_corrected = signal[keep] * r**2

    # Ozone absorption is not in Klett's molecular term: take it out of the signal with
    # the two-way ozone transmission from the ground (a sounding or climatology would
    # give alpha_o3; here the file's truth).
    dr = np.diff(r).mean()  # 7.49 m: c·bin_width_s/2, not a round 7.5
    alpha_o3 = truth.alpha_o3.values[keep]
    tau_o3 = np.cumsum(alpha_o3) * dr - 0.5 * alpha_o3 * dr  # to each bin centre
    range_corrected = range_corrected * np.exp(2 * tau_o3)

    # 60 m bins: over 7.5 m the photon noise at 7 km is ~20 %. The truth's lidar ratio
    # is 0 where there is no aerosol, which is exact there (no aerosol extinction).
    altitude = _blocks(raw.altitude.values[keep])
    range_corrected = _blocks(range_corrected)
    beta_mol = _blocks(truth.beta_mol.values[keep])          # from the sounding
    lidar_ratio = _blocks(truth.lidar_ratio_aer.values[keep]) * lidar_ratio_scale
    beta_aer_true = _blocks(truth.beta_aer.values[keep])
    bin_length = dr * BLOCK

    # The reference: the middle of the clean region, fitted over all of it (the library
    # scales beta_mol to the signal over index ± half-width, then Klett integrates down).
    in_ref = np.flatnonzero((altitude >= REFERENCE[0]) & (altitude <= REFERENCE[1]))
    index_reference = int(in_ref[in_ref.size // 2])
    half_width = in_ref.size // 2
    beta_aer_reference = (reference_scattering_ratio - 1.0) * beta_mol[index_reference]

    beta_aer = klett_backscatter_aerosol(
        range_corrected, lidar_ratio, beta_mol, index_reference, half_width,
        beta_aer_reference, bin_length,
        # the channel's own: the library's default (8.74 sr) is the Cabannes line's,
        # this channel's 1 nm filter passes the Cabannes line and the nearest rotational
        # Raman lines (8.70 sr at 532 nm, docs/model.md §4a)
        lidar_ratio_molecular=float(ch.molecular_lidar_ratio))

    return xr.Dataset(
        {"beta_aer": ("altitude", beta_aer, {"units": "m-1 sr-1"}),
         "beta_aer_true": ("altitude", beta_aer_true, {"units": "m-1 sr-1"}),
         "lidar_ratio": ("altitude", lidar_ratio, {"units": "sr"})},
        coords={"altitude": ("altitude", altitude, {"units": "m"})},
        attrs={"channel": channel, "reference_altitude_m": float(altitude[index_reference]),
               "bin_length_m": bin_length})


def score(retrieved: xr.Dataset) -> dict:
    """Relative error of the aerosol backscatter in each layer's interior: the median
    (signed: the bias) and the 90th percentile of its magnitude, over the 60 m bins."""
    scores = {}
    for name, (bottom, top) in LAYERS.items():
        layer = retrieved.sel(altitude=slice(bottom, top))
        rel = (layer.beta_aer / layer.beta_aer_true - 1.0).values
        scores[name] = {
            "bins": int(rel.size),
            "beta_aer_true": float(layer.beta_aer_true.mean()),
            "beta_aer": float(layer.beta_aer.mean()),
            "median_rel_error": float(np.median(rel)),
            "p90_abs_rel_error": float(np.percentile(np.abs(rel), 90)),
        }
    return scores


def print_table(scores: dict, retrieved: xr.Dataset) -> None:
    print(f"Klett retrieval of {retrieved.channel}, reference at "
          f"{retrieved.reference_altitude_m / 1e3:.2f} km, "
          f"{retrieved.bin_length_m:.1f} m bins")
    print(f"{'layer':<15} {'km':>9} {'bins':>4} {'true β_aer':>11} {'retrieved':>10} "
          f"{'median err':>10} {'p90 |err|':>9}")
    for name, s in scores.items():
        bottom, top = LAYERS[name]
        print(f"{name:<15} {bottom / 1e3:4.2f}-{top / 1e3:4.2f} {s['bins']:>4} "
              f"{s['beta_aer_true']:11.3e} {s['beta_aer']:10.3e} "
              f"{100 * s['median_rel_error']:+9.2f}% {100 * s['p90_abs_rel_error']:8.2f}%")
    print("β_aer in m-1 sr-1 (layer means); errors per 60 m bin, relative to the truth")


def main(profiles: int = PROFILES, seed: int = SEED, lidar_ratio_scale: float = 1.0,
         reference_scattering_ratio: float = 1.0, raw: xr.Dataset | None = None,
         verbose: bool = True) -> dict:
    """Simulates (unless ``raw`` is given), retrieves, scores; returns the scores per layer."""
    if raw is None:
        raw = simulate(profiles, seed)
    retrieved = retrieve(raw, lidar_ratio_scale=lidar_ratio_scale,
                         reference_scattering_ratio=reference_scattering_ratio)
    scores = score(retrieved)
    if verbose:
        print_table(scores, retrieved)
    return scores


if __name__ == "__main__":
    main()
