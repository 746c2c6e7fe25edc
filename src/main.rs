//! `lidarsim`: a thin command line over the library (argument parsing and error reporting).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use lidarsim::cli_values;
use lidarsim::shard::ShardArg;

/// Help and version go to stdout as clap prints them; a usage error is one line.
fn usage_error(e: clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    if matches!(
        e.kind(),
        ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        let _ = e.print();
        return if e.use_stderr() {
            ExitCode::from(2)
        } else {
            ExitCode::SUCCESS
        };
    }
    // the paragraph before clap's usage and tips, on one line
    let text = e.render().to_string();
    let message: Vec<&str> = text
        .lines()
        .take_while(|l| !l.trim().is_empty())
        .map(str::trim)
        .collect();
    let message = message.join(" ");
    let message = message.strip_prefix("error: ").unwrap_or(&message);
    lidarsim::tell!("lidarsim: error: {message} (see lidarsim --help)");
    ExitCode::from(2)
}

/// Monte Carlo simulator of photon-counting backscatter lidar signals.
#[derive(Parser)]
#[command(name = "lidarsim", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// The deterministic per-bin model: atmosphere, expected counts per shot, Eq. 4 S/N.
    Expect {
        /// Scenario config (TOML).
        config: PathBuf,
        /// Override a config key: --set instrument.pulse_energy_j=0.1 (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Write the per-bin CSV to PATH (`-` for stdout) instead of the table.
        #[arg(long, value_name = "PATH")]
        csv: Option<PathBuf>,
        /// The receiver channel to show (default: the first).
        #[arg(long, value_name = "NAME")]
        channel: Option<String>,
    },
    /// S/N against altitude and accumulation time (the paper's Figs. 2–3).
    SnrMap {
        /// Scenario config (TOML).
        config: PathBuf,
        /// Override a config key (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Output PNG.
        #[arg(long, value_name = "OUT.png")]
        png: PathBuf,
        /// Also write the map as CSV (altitude_m, accumulation_time_s, snr).
        #[arg(long, value_name = "PATH")]
        csv: Option<PathBuf>,
        /// The receiver channel to map (default: the first).
        #[arg(long, value_name = "NAME")]
        channel: Option<String>,
    },
    /// The Monte Carlo: draws photon counts and writes a raw lidar file (HDF5).
    Simulate {
        /// Scenario config (TOML).
        config: PathBuf,
        /// Override a config key (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Output raw file (HDF5, netCDF-4 readable).
        #[arg(short = 'o', long = "output", value_name = "OUT.h5")]
        output: PathBuf,
        /// Random seed (default: simulation.seed); 0 to 2^64-1.
        #[arg(long, allow_negative_numbers = true, value_parser = cli_values::seed)]
        seed: Option<u64>,
        /// Number of profiles (default: acquisition.profiles); 1 to 1e12, `1e6` accepted.
        #[arg(long, allow_negative_numbers = true, value_parser = cli_values::profiles)]
        profiles: Option<usize>,
        /// auto, shot or aggregate (default: simulation.method).
        #[arg(long, value_enum)]
        method: Option<lidarsim::config::Method>,
        /// Also store signal, background and dark counts separately.
        #[arg(long)]
        components: bool,
        /// compact (each truth at the dimensions of what it depends on) or per-profile
        /// (also format 3's (profile, channel, bin) arrays of a changing scene); default
        /// simulation.truth.
        #[arg(long, value_enum)]
        truth: Option<lidarsim::config::TruthForm>,
        /// With --method auto: largest KS distance per bin to the exact law a faster
        /// approximation may have, in (0, 0.01] (e.g. 1e-3); default exact.
        #[arg(long, allow_negative_numbers = true, value_parser = cli_values::tolerance)]
        tolerance: Option<f64>,
        /// Worker threads, 1 to 1024 (default: all cores); results do not depend on it.
        #[arg(long, allow_negative_numbers = true, value_parser = cli_values::threads)]
        threads: Option<usize>,
        /// raw (HDF5 raw lidar file) or scc (EARLINET SCC raw NetCDF, ground runs).
        #[arg(long, value_enum, default_value_t = lidarsim::commands::OutputFormat::Raw)]
        format: lidarsim::commands::OutputFormat,
        /// Write shard K of N of the run only (its profiles, for `merge`); `auto` reads
        /// K and N from an array job's environment (SLURM_ARRAY_TASK_ID, ...).
        #[arg(long, value_name = "K/N|auto", value_parser = cli_values::shard)]
        shard: Option<ShardArg>,
        /// A Δ90 depolarization calibration run: the receiver's polarization plane
        /// rotated by +45° or −45° (`--set instrument.receiver_rotation_deg=±45`).
        #[arg(long, value_enum)]
        calibration: Option<Calibration>,
        /// With --calibration: draw with the seed itself (the noise of the measurement
        /// with that seed), not with the seed derived from it and the rotation.
        #[arg(long, requires = "calibration")]
        same_noise: bool,
        /// Also write every recorded event (time-tagged photons with their truth) to
        /// this HDF5 file (docs/photons.md); shot-level runs of photon counters only.
        #[arg(long, value_name = "PHOTONS.h5")]
        photons: Option<PathBuf>,
    },
    /// Profiles of a photon file's events (`simulate --photons`) at any range
    /// resolution and shot accumulation, with their truth (docs/photons.md).
    Histogram {
        /// The photon file.
        photons: PathBuf,
        /// The histogram file (HDF5).
        #[arg(short = 'o', long = "output", value_name = "OUT.h5")]
        output: PathBuf,
        /// Bin width, m (default: the run's).
        #[arg(long, value_name = "M")]
        bin_width: Option<f64>,
        /// Shots per profile (default: the run's).
        #[arg(long, value_name = "N")]
        shots: Option<u64>,
    },
    /// Merges the shards of a run (`simulate --shard K/N`) into the file of the whole run.
    Merge {
        /// The merged raw file (the file the whole run writes).
        output: PathBuf,
        /// Every shard of the run, once, in any order.
        #[arg(required = true, value_name = "SHARD.h5")]
        shards: Vec<PathBuf>,
    },
    /// Onboard averaging of shot-level counts: the downlinked product and the report.
    Onboard {
        /// Scenario config (TOML); not with --combine or --file.
        #[arg(required_unless_present_any = ["combine", "file"])]
        config: Option<PathBuf>,
        /// Override a config key (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// none, uniform:N, caliop, or a scheme file (TOML) (repeatable: the first one's product is written).
        #[arg(long, value_name = "NAME|FILE")]
        scheme: Vec<String>,
        /// The downlinked product (HDF5, one group per region).
        #[arg(
            short = 'o',
            long = "output",
            value_name = "PRODUCT.h5",
            required_unless_present = "combine"
        )]
        output: Option<PathBuf>,
        /// One CSV row per scheme and region (`-` for stdout); with --combine, stdout when absent.
        #[arg(long, value_name = "PATH")]
        report: Option<PathBuf>,
        /// Also write the native shot-level raw file of the same draw.
        #[arg(long, value_name = "RAW.h5")]
        raw: Option<PathBuf>,
        /// Random seed (default: simulation.seed).
        #[arg(long, allow_negative_numbers = true, value_parser = cli_values::seed)]
        seed: Option<u64>,
        /// Bits per downlinked count, for the data rate (1 to 64).
        #[arg(long, default_value_t = 16, allow_negative_numbers = true, value_parser = cli_values::word_bits)]
        word_bits: u32,
        /// Draw shard K of N of the run only (whole frames of shots; its product shard for
        /// `merge`); `auto` reads K and N from an array job's environment.
        #[arg(long, value_name = "K/N|auto", value_parser = cli_values::shard)]
        shard: Option<ShardArg>,
        /// Write the shard's report sums (JSON) for --combine; with --shard.
        #[arg(long, value_name = "PART.json", requires = "shard")]
        partial: Option<PathBuf>,
        /// The report of the whole run from the partials of all its shards.
        #[arg(long, value_name = "PART.json", num_args = 1..,
              conflicts_with_all = ["config", "set", "scheme", "output", "raw", "seed", "word_bits", "shard", "partial"])]
        combine: Vec<PathBuf>,
    },
    /// Instrument design grid from the deterministic model: metrics over varied config keys.
    Sweep {
        /// Scenario config (TOML).
        config: PathBuf,
        /// Override a config key (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// A key to vary: KEY=START..STOP:N (linear) or KEY=START..STOP:log:N (repeatable).
        #[arg(long, value_name = "KEY=START..STOP[:log]:N")]
        vary: Vec<String>,
        /// snr_at:Zkm, max_altitude:snr=X, time_to_snr:X@Zkm, mean_laser_power_w, pulses_in_flight (repeatable).
        #[arg(long, value_name = "METRIC")]
        metric: Vec<String>,
        /// One CSV row per grid point (`-` for stdout).
        #[arg(long, value_name = "PATH")]
        csv: PathBuf,
        /// The first metric as a line (one key) or heatmap (two keys).
        #[arg(long, value_name = "OUT.png")]
        png: Option<PathBuf>,
    },
    /// Draws a raw file's counts per shot against along-track distance (or time) and altitude.
    Curtain {
        /// The raw lidar file (`simulate -o`).
        raw: PathBuf,
        /// Output PNG.
        #[arg(long, value_name = "OUT.png")]
        png: PathBuf,
        /// The channel to draw (default: the first).
        #[arg(long, value_name = "NAME")]
        channel: Option<String>,
    },
    /// The quicklook of a raw file, a merged file or an onboard product: the
    /// range-corrected signal on a log colour scale against time (or along-track
    /// distance) and altitude, the volume depolarization of a ∥/⊥ pair, the truth with
    /// --truth (docs/figures.md)
    Quicklook {
        /// The raw file (`simulate -o`, `merge -o`) or onboard product (`onboard -o`).
        file: PathBuf,
        /// Output PNG.
        #[arg(long, value_name = "OUT.png")]
        png: PathBuf,
        /// The channel to draw (default: the first).
        #[arg(long, value_name = "NAME")]
        channel: Option<String>,
        /// Also draw the truth's attenuated backscatter on the same colour scale.
        #[arg(long)]
        truth: bool,
        /// The altitudes drawn, km above sea level, e.g. `0,15` (default: from the
        /// lowest recorded bin after the pre-trigger bins to the window's top or 40 km).
        #[arg(long, value_name = "LO,HI", allow_negative_numbers = true, value_parser = cli_values::altitude_range_km)]
        altitude_range: Option<(f64, f64)>,
        /// Channels drawn as panels stacked on one x axis, top to bottom, e.g.
        /// `532_parallel,532_perpendicular` (instead of --channel).
        #[arg(
            long,
            value_name = "A,B,...",
            value_delimiter = ',',
            conflicts_with = "channel"
        )]
        channels: Vec<String>,
        /// The x axis: time (UTC), latitude (an orbit's latitude and longitude),
        /// along-track (km), profile, or auto (time for a ground file, latitude for an orbit's).
        #[arg(long, value_name = "AXIS", default_value = "auto", value_parser = cli_values::x_axis)]
        x_axis: lidarsim::figures::quicklook::XAxis,
        /// Grey the cells where most bins have an S/N below X, estimated from the counts
        /// (signal over the square root of the recorded photoelectrons).
        #[arg(long, value_name = "X", allow_negative_numbers = true, value_parser = cli_values::mask_snr)]
        mask_snr: Option<f64>,
    },
    /// Converts a raw file (ground run) to the EARLINET SCC raw NetCDF format.
    ExportScc {
        /// The raw lidar file (`simulate -o`).
        raw: PathBuf,
        /// Output SCC NetCDF file.
        out: PathBuf,
        #[command(flatten)]
        ids: SccIds,
    },
    /// Writes the two Δ90 depolarization calibration runs (`simulate --calibration
    /// plus45`, `minus45`) as one SCC raw NetCDF calibration measurement.
    ExportSccCalibration {
        /// The +45° run's raw file (`simulate --calibration plus45 -o`).
        plus45: PathBuf,
        /// The −45° run's raw file (`simulate --calibration minus45 -o`).
        minus45: PathBuf,
        /// Output SCC NetCDF file.
        out: PathBuf,
        /// Range (m) where the SCC takes the calibration factor: Pol_Calib_Range_Min,Max.
        #[arg(long, value_name = "MIN,MAX", value_parser = cli_values::pol_calib_range_m)]
        pol_calib_range: (f64, f64),
        #[command(flatten)]
        ids: SccIds,
    },
    /// Statistical check of the simulator against Eq. 4, or (--file) of a raw file's counts
    /// against the expectation it carries; exit 0 when consistent, 1 when not.
    Validate {
        /// Scenario config (TOML); not with --combine or --file.
        #[arg(required_unless_present_any = ["combine", "file"])]
        config: Option<PathBuf>,
        /// Override a config key (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Number of independent profiles to draw.
        #[arg(long, default_value_t = 1000, allow_negative_numbers = true, value_parser = cli_values::realizations)]
        realizations: usize,
        /// auto, shot or aggregate (default: simulation.method).
        #[arg(long, value_enum)]
        method: Option<lidarsim::config::Method>,
        /// Random seed (default: simulation.seed); 0 to 2^64-1.
        #[arg(long, allow_negative_numbers = true, value_parser = cli_values::seed)]
        seed: Option<u64>,
        /// Also write the full report (every bin) as JSON.
        #[arg(long, value_name = "PATH", conflicts_with = "partial")]
        json: Option<PathBuf>,
        /// Draw shard K of N of the realizations only (K/N, or auto from an array job's
        /// environment); with --partial.
        #[arg(long, value_name = "K/N|auto", value_parser = cli_values::shard, requires = "partial")]
        shard: Option<ShardArg>,
        /// Write the shard's sufficient statistics (JSON) for --combine; with --shard.
        #[arg(long, value_name = "PART.json", requires = "shard")]
        partial: Option<PathBuf>,
        /// The verdict of the whole run from the partials of all its shards.
        #[arg(long, value_name = "PART.json", num_args = 1..,
              conflicts_with_all = ["config", "set", "shard", "partial", "method", "seed", "realizations"])]
        combine: Vec<PathBuf>,
        /// Check the counts of a raw file (simulate -o, a merge, a copy) against the
        /// expectation and detector law the file carries (expected_*, n_shots,
        /// pulse_energy, dead_time), profile by profile, with validate's calibrated mean
        /// and variance tests; exit 0 CONSISTENT, 1 INCONSISTENT (false-alarm rate below
        /// 1e-3), 2 for a file that is not a raw file. Dead-time channels are judged only
        /// in profiles at the nominal pulse energy (validation/README.md §1c).
        #[arg(long, value_name = "RAW.h5",
              conflicts_with_all = ["config", "set", "shard", "partial", "method", "seed", "realizations", "combine"])]
        file: Option<PathBuf>,
    },
}

/// An allocation that fails ends the run with one line and exit status 2, never an
/// abort (issue 18; `lidarsim::resources::NoAbortAllocator`).
#[global_allocator]
static ALLOCATOR: lidarsim::resources::NoAbortAllocator = lidarsim::resources::NoAbortAllocator;

fn main() -> ExitCode {
    lidarsim::resources::one_heap_under_an_address_space_limit();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return usage_error(e),
    };
    if let Err(e) = lidarsim::safe_file::install_signal_handlers() {
        lidarsim::tell!("lidarsim: error: {e}");
        return ExitCode::from(2);
    }
    let result = match &cli.command {
        Command::Expect {
            config,
            set,
            csv,
            channel,
        } => lidarsim::commands::expect(config, set, csv.as_deref(), channel.as_deref())
            .map(|()| true),
        Command::SnrMap {
            config,
            set,
            png,
            csv,
            channel,
        } => lidarsim::commands::snr_map(config, set, png, csv.as_deref(), channel.as_deref())
            .map(|()| true),
        Command::Simulate {
            config,
            set,
            output,
            seed,
            profiles,
            method,
            components,
            truth,
            tolerance,
            threads,
            format,
            shard,
            calibration,
            same_noise,
            photons,
        } => shard
            .map(ShardArg::resolve)
            .transpose()
            .and_then(|shard| {
                let opts = lidarsim::simulate::RunOptions {
                    output: output.clone(),
                    seed: *seed,
                    profiles: *profiles,
                    method: *method,
                    components: components.then_some(true),
                    truth: *truth,
                    tolerance: *tolerance,
                    progress: std::io::IsTerminal::is_terminal(&std::io::stderr()),
                    command_line: lidarsim::output::raw_file::content::history_command(
                        std::env::args(),
                    ),
                    shard,
                    cancel: None,
                    photons: photons.clone(),
                };
                match calibration {
                    Some(c) => lidarsim::commands::simulate_calibration(
                        config,
                        set,
                        &opts,
                        *threads,
                        *format,
                        c.rotation_deg(),
                        *same_noise,
                    ),
                    None => lidarsim::commands::simulate_as(config, set, &opts, *threads, *format),
                }
            })
            .map(|()| true),
        Command::Histogram {
            photons,
            output,
            bin_width,
            shots,
        } => lidarsim::commands::histogram(photons, output, *bin_width, *shots).map(|()| true),
        Command::Merge { output, shards } => {
            lidarsim::commands::merge(output, shards).map(|()| true)
        }
        Command::Onboard {
            config,
            set,
            scheme,
            output,
            report,
            raw,
            seed,
            word_bits,
            shard,
            partial,
            combine,
        } => match (config, output) {
            _ if !combine.is_empty() => {
                lidarsim::commands::onboard_combine(combine, report.as_deref()).map(|()| true)
            }
            (Some(config), Some(output)) => shard
                .map(ShardArg::resolve)
                .transpose()
                .and_then(|shard| {
                    let opts = lidarsim::onboard::run::OnboardOptions {
                        schemes: scheme.clone(),
                        output: output.clone(),
                        report: report.clone(),
                        raw: raw.clone(),
                        seed: *seed,
                        word_bits: *word_bits,
                        shard,
                        partial: partial.clone(),
                        command_line: lidarsim::output::raw_file::content::history_command_omitting(
                            std::env::args(),
                            &lidarsim::output::raw_file::content::PRODUCT_HISTORY_OMITS,
                        ),
                    };
                    lidarsim::onboard::run::run(config, set, &opts)
                })
                .map(|()| true),
            _ => Err(lidarsim::error::Error::Unsupported(
                "onboard needs a CONFIG and -o PRODUCT.h5, or --combine PART.json ...".into(),
            )),
        },
        Command::Sweep {
            config,
            set,
            vary,
            metric,
            csv,
            png,
        } => lidarsim::commands::sweep(config, set, vary, metric, csv, png.as_deref(), None)
            .map(|()| true),
        Command::Curtain { raw, png, channel } => {
            lidarsim::commands::curtain(raw, png, channel.as_deref()).map(|()| true)
        }
        Command::Quicklook {
            file,
            png,
            channel,
            truth,
            altitude_range,
            channels,
            x_axis,
            mask_snr,
        } => {
            let view = lidarsim::figures::quicklook::View {
                altitude_range_km: *altitude_range,
                x_axis: *x_axis,
                mask_snr: *mask_snr,
            };
            let channels: Vec<String> = channel.iter().cloned().chain(channels.clone()).collect();
            lidarsim::figures::quicklook::run(file, png, &channels, *truth, view).map(|()| true)
        }
        Command::ExportScc { raw, out, ids } => {
            lidarsim::commands::export_scc(raw, out, &ids.options()).map(|()| true)
        }
        Command::ExportSccCalibration {
            plus45,
            minus45,
            out,
            pol_calib_range,
            ids,
        } => {
            let opts = lidarsim::output::scc::SccCalibrationOptions {
                scc: ids.options(),
                pol_calib_range_m: *pol_calib_range,
            };
            lidarsim::commands::export_scc_calibration(plus45, minus45, out, &opts).map(|()| true)
        }
        Command::Validate {
            config,
            set,
            realizations,
            method,
            seed,
            json,
            shard,
            partial,
            combine,
            file,
        } => {
            let opts = lidarsim::validate::ValidateOptions {
                realizations: *realizations,
                method: *method,
                seed: *seed,
                json: json.clone(),
            };
            match (config, shard, partial) {
                _ if let Some(raw) = file => {
                    lidarsim::commands::validate_file(raw, json.as_deref())
                }
                _ if !combine.is_empty() => {
                    lidarsim::commands::validate_combine(combine, json.as_deref())
                }
                (Some(config), Some(shard), Some(partial)) => shard
                    .resolve()
                    .and_then(|s| {
                        lidarsim::commands::validate_partial(config, set, &opts, s, partial)
                    })
                    .map(|()| true),
                (Some(config), ..) => lidarsim::commands::validate(config, set, &opts),
                (None, ..) => Err(lidarsim::error::Error::Unsupported(
                    "validate needs a CONFIG, or --combine PART.json ...".into(),
                )),
            }
        }
    };
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            lidarsim::tell!("lidarsim: error: {e}");
            ExitCode::from(2)
        }
    }
}

/// The SCC identifiers of `export-scc` and `export-scc-calibration`.
#[derive(clap::Args, Debug)]
struct SccIds {
    /// Measurement_ID, YYYYMMDDccNN (default: start date, station, 00).
    #[arg(long, value_name = "ID")]
    measurement_id: Option<String>,
    /// Two-letter EARLINET station call sign.
    #[arg(long, default_value = "ls", value_name = "CC")]
    station: String,
    /// SCC channel IDs of the file's channels, in order (e.g. 1023,1024); for a
    /// calibration, of its channels, the +45° ones first.
    #[arg(long, value_delimiter = ',', value_name = "ID,...")]
    channel_ids: Option<Vec<i32>>,
}

impl SccIds {
    fn options(&self) -> lidarsim::output::scc::SccOptions {
        lidarsim::output::scc::SccOptions {
            measurement_id: self.measurement_id.clone(),
            station_id: self.station.clone(),
            channel_ids: self.channel_ids.clone(),
        }
    }
}

/// `simulate --calibration`: the two runs of the Δ90 depolarization calibration.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum Calibration {
    /// The receiver's polarization plane rotated by +45°.
    Plus45,
    /// Rotated by −45°.
    Minus45,
}

impl Calibration {
    /// The run's `instrument.receiver_rotation_deg`: ±45.
    fn rotation_deg(self) -> f64 {
        match self {
            Calibration::Plus45 => 45.0,
            Calibration::Minus45 => -45.0,
        }
    }
}
