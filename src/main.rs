//! `lidarsim`: a thin command line over the library (argument parsing and error reporting).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

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
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Expect { config, set, csv } => {
            lidarsim::commands::expect(config, set, csv.as_deref())
        }
        Command::SnrMap {
            config,
            set,
            png,
            csv,
        } => lidarsim::commands::snr_map(config, set, png, csv.as_deref()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("lidarsim: error: {e}");
            ExitCode::from(2)
        }
    }
}
