//! The `expect` outputs: the per-bin CSV of docs/config.md and a terminal table.

use std::io::{self, Write};

use crate::scenario::{ExpectedProfile, Scenario};

/// CSV header: the docs/config.md columns, then the S/N with an estimated background.
pub const CSV_COLUMNS: [&str; 12] = [
    "altitude_m",
    "range_m",
    "beta_mol",
    "beta_aer",
    "beta_cld",
    "alpha_total",
    "t2",
    "signal",
    "background",
    "dark",
    "snr",
    "snr_bkg_estimated",
];

/// Writes one row per bin, SI units, counts per shot per bin; `snr` is Eq. 4 after
/// `shots` shots; `snr_bkg_estimated` is empty when no signal-free bins exist.
pub fn write_csv(w: &mut dyn Write, e: &ExpectedProfile, shots: f64) -> io::Result<()> {
    writeln!(w, "{}", CSV_COLUMNS.join(","))?;
    let snr = e.snr_eq4(shots);
    let snr_est = e.snr_estimated_background(shots);
    for i in 0..e.n_bins() {
        let est = snr_est
            .as_ref()
            .map(|v| format!("{:e}", v[i]))
            .unwrap_or_default();
        writeln!(
            w,
            "{},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{}",
            e.altitude_m[i],
            e.range_m[i],
            e.point[i].beta_mol,
            e.point[i].beta_aer,
            e.point[i].beta_cld,
            e.point[i].alpha_total,
            e.t2[i],
            e.signal[i],
            e.background,
            e.dark,
            snr[i],
            est
        )?;
    }
    Ok(())
}

/// A table for a person: a summary, then one line per bin.
pub fn write_table(w: &mut dyn Write, sc: &Scenario, e: &ExpectedProfile) -> io::Result<()> {
    let cfg = &sc.loaded.config;
    let shots = sc.instrument.rep_rate_hz * sc.accumulation_time_s();
    writeln!(w, "{} — {}", cfg.name, cfg.description)?;
    writeln!(
        w,
        "  {} bins of {:.1} m, {:.0} shots per profile (fL = {} Hz, TC = {} s)",
        e.n_bins(),
        sc.geometry.bin_range_m,
        shots,
        sc.instrument.rep_rate_hz,
        sc.accumulation_time_s()
    )?;
    writeln!(
        w,
        "  per shot per bin: background {:.3e}, dark {:.3e} counts; {} signal-free bins for the background",
        e.background, e.dark, e.background_bins
    )?;
    writeln!(w)?;
    writeln!(
        w,
        "{:>9} {:>10} {:>10} {:>10} {:>10} {:>10} {:>9}",
        "alt (km)", "beta_tot", "T2", "signal", "bkg+dark", "S/N Eq.4", "S/N est."
    )?;
    let snr = e.snr_eq4(shots);
    let est = e.snr_estimated_background(shots);
    for i in 0..e.n_bins() {
        let est_s = est
            .as_ref()
            .map(|v| format!("{:9.2}", v[i]))
            .unwrap_or_else(|| format!("{:>9}", "-"));
        writeln!(
            w,
            "{:9.3} {:10.3e} {:10.4} {:10.3e} {:10.3e} {:10.2} {}",
            e.altitude_m[i] / 1e3,
            e.point[i].beta_mol + e.point[i].beta_aer + e.point[i].beta_cld,
            e.t2[i],
            e.signal[i],
            e.background + e.dark,
            snr[i],
            est_s
        )?;
    }
    Ok(())
}
