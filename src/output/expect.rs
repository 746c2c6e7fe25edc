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

/// The CSV's columns ([`CSV_COLUMNS`], in that order), one value per bin: SI units,
/// counts per shot per bin; `snr` is Eq. 4 after `shots` shots; `snr_bkg_estimated`
/// is NaN throughout when no signal-free bins exist. The CSV and the Python module's
/// `expect` (docs/python.md) are both these numbers.
pub fn columns(e: &ExpectedProfile, shots: f64) -> Vec<(&'static str, Vec<f64>)> {
    let n = e.n_bins();
    let point = |f: fn(&crate::atmosphere::Optics) -> f64| e.point.iter().map(f).collect();
    let values: [Vec<f64>; 12] = [
        e.altitude_m.clone(),
        e.range_m.clone(),
        point(|o| o.beta_mol),
        point(|o| o.beta_aer),
        point(|o| o.beta_cld),
        point(|o| o.alpha_total),
        e.t2.clone(),
        e.signal.clone(),
        vec![e.background; n],
        vec![e.dark; n],
        e.snr_eq4(shots),
        e.snr_estimated_background(shots)
            .unwrap_or_else(|| vec![f64::NAN; n]),
    ];
    CSV_COLUMNS.into_iter().zip(values).collect()
}

/// What the Python module's `expect` returns (docs/python.md): every variable a raw
/// file of `lidar` holds before its first profile but the `profile` coordinate, the
/// file's names, dimensions, values and attributes ([`memory::fixed_variables`]), then
/// the CSV's two S/N ([`snr_variables`]); in a scene that changes along the track, the
/// expectations the file holds per profile (`expected_signal`, …) come as the first
/// column's (channel, bin). And the CSV's shots per profile (`rep_rate · accumulation
/// time`). `command_line` goes to the `history` the file would have.
///
/// [`memory::fixed_variables`]: crate::output::raw_file::memory::fixed_variables
pub fn model_variables(
    lidar: &crate::scenario::Lidar,
    command_line: &str,
) -> crate::error::Result<(Vec<crate::output::raw_file::memory::MemoryVariable>, f64)> {
    use crate::output::raw_file::{Dims, PROFILE_DIM, content, memory};
    // a changing scene's expectations per profile (format 3's layout), replaced below
    // by the first column's
    let opts = crate::simulate::RunOptions {
        command_line: command_line.into(),
        truth: Some(crate::config::TruthForm::PerProfile),
        ..Default::default()
    };
    let plan = crate::simulate::plan(lidar, &opts, None)?;
    let first = lidar.first();
    let mut spec = plan.spec;
    if plan.scene.is_some() {
        let columns = [plan.expected.as_slice()];
        let shots = first.shots_per_profile();
        let first_column = content::variables(
            lidar,
            &plan.expected,
            &columns,
            &crate::output::raw_file::truth::aerosol_species_of(&columns),
            shots,
            content::TruthLayout::Static,
        );
        for v in spec.variables.iter_mut() {
            let same = first_column.iter().find(|f| f.name == v.name);
            if let (Dims::ProfileChannelBin, Some(f)) = (v.dims, same) {
                *v = f.clone();
            }
        }
    }
    let mut vars = memory::fixed_variables(spec)?;
    vars.retain(|v| !v.dims.contains(&PROFILE_DIM));
    vars.extend(snr_variables(lidar, &plan.expected));
    Ok((
        vars,
        first.instrument.rep_rate_hz * first.accumulation_time_s(),
    ))
}

/// The CSV's two S/N columns of every channel of `lidar` (`expected` in its order) as
/// (channel, bin) variables beside the raw file's truth (the Python module's `expect`):
/// `snr`, Eq. 4 with M = rep_rate · accumulation_time shots as the paper writes it (the
/// file's `snr_eq4` takes the profile's whole number of shots), and `snr_bkg_estimated`,
/// NaN where a channel has no signal-free bins.
pub fn snr_variables(
    lidar: &crate::scenario::Lidar,
    expected: &[ExpectedProfile],
) -> [crate::output::raw_file::memory::MemoryVariable; 2] {
    use crate::output::raw_file::{AttrValue, BIN_DIM, CHANNEL_DIM, memory};
    let n_bins = expected.first().map_or(0, ExpectedProfile::n_bins);
    let per_channel = |f: &dyn Fn(&ExpectedProfile, f64) -> Vec<f64>| -> Vec<f64> {
        lidar
            .channels
            .iter()
            .zip(expected)
            .flat_map(|(sc, e)| f(e, sc.instrument.rep_rate_hz * sc.accumulation_time_s()))
            .collect()
    };
    let text = |k: &str, v: &str| (k.to_string(), AttrValue::Str(v.to_string()));
    let variable = |name: &str, long_name: &str, data| memory::MemoryVariable {
        name: name.into(),
        dims: vec![CHANNEL_DIM, BIN_DIM],
        shape: vec![expected.len(), n_bins],
        attributes: vec![
            text("long_name", long_name),
            text("units", "1"),
            text("coordinates", "altitude range"),
        ],
        data: memory::Array::F64(data),
    };
    [
        variable(
            CSV_COLUMNS[10],
            "Eq. 4 signal-to-noise ratio of rep_rate x accumulation_time shots (expect --csv)",
            per_channel(&|e, shots| e.snr_eq4(shots)),
        ),
        variable(
            CSV_COLUMNS[11],
            "signal-to-noise ratio with the background estimated from the signal-free bins (expect --csv)",
            per_channel(&|e, shots| {
                e.snr_estimated_background(shots)
                    .unwrap_or_else(|| vec![f64::NAN; n_bins])
            }),
        ),
    ]
}

/// Writes one row per bin of [`columns`] (`altitude_m` and `range_m` as decimals, the
/// rest in scientific notation; `snr_bkg_estimated` empty when there is none).
pub fn write_csv(w: &mut dyn Write, e: &ExpectedProfile, shots: f64) -> io::Result<()> {
    writeln!(w, "{}", CSV_COLUMNS.join(","))?;
    let cols = columns(e, shots);
    let estimated = e.snr_estimated_background(shots).is_some();
    for i in 0..e.n_bins() {
        let cells: Vec<String> = cols
            .iter()
            .enumerate()
            .map(|(k, (_, v))| match k {
                0 | 1 => format!("{}", v[i]),
                11 if !estimated => String::new(),
                _ => format!("{:e}", v[i]),
            })
            .collect();
        writeln!(w, "{}", cells.join(","))?;
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
