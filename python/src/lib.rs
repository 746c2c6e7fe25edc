//! The Python module `lidarsim._lidarsim` (docs/python.md): the library's commands,
//! called in the same process without the GIL, their errors raised as Python
//! exceptions with the CLI's one-line message (`ValueError` for bad input, `OSError`
//! for files). `lidarsim/__init__.py` builds the xarray Datasets from what these
//! return.

use std::path::PathBuf;

use lidarsim::error::Error;
use numpy::IntoPyArray;
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The CLI's error as a Python exception: files are `OSError`, the rest `ValueError`.
fn raise(e: Error) -> PyErr {
    let message = e.to_string();
    match e {
        Error::Io { .. } | Error::Output { .. } => PyOSError::new_err(message),
        _ => PyValueError::new_err(message),
    }
}

/// Loads and checks `config` with `overrides` (`KEY=VALUE`, as `--set`), as every
/// command does; returns the channels' names.
#[pyfunction]
fn check(py: Python<'_>, config: PathBuf, overrides: Vec<String>) -> PyResult<Vec<String>> {
    py.allow_threads(|| {
        let lidar = lidarsim::scenario::Lidar::load(&config, &overrides)?;
        Ok(lidar.channel_names())
    })
    .map_err(raise)
}

/// `lidarsim expect CONFIG --csv`: the deterministic model of one channel per bin, as
/// the CSV's columns (numpy arrays), with the shots of a profile and the channel.
#[pyfunction]
#[pyo3(signature = (config, overrides, channel=None))]
fn expect<'py>(
    py: Python<'py>,
    config: PathBuf,
    overrides: Vec<String>,
    channel: Option<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let (columns, shots) = py
        .allow_threads(|| -> lidarsim::error::Result<_> {
            let sc = lidarsim::commands::load_channel(&config, &overrides, channel.as_deref())?;
            let e = sc.expected()?;
            let shots = sc.instrument.rep_rate_hz * sc.accumulation_time_s();
            Ok((lidarsim::output::expect::columns(&e, shots), shots))
        })
        .map_err(raise)?;
    let out = PyDict::new_bound(py);
    for (name, values) in columns {
        out.set_item(name, values.into_pyarray_bound(py))?;
    }
    out.set_item("shots_per_profile", shots)?;
    Ok(out)
}

/// `lidarsim simulate CONFIG -o OUTPUT`: writes the raw file exactly as the CLI does
/// (same seed, same counts and truth; the `history` attribute names this call).
#[pyfunction]
#[pyo3(signature = (config, overrides, output, profiles=None, seed=None))]
fn simulate(
    py: Python<'_>,
    config: PathBuf,
    overrides: Vec<String>,
    output: PathBuf,
    profiles: Option<usize>,
    seed: Option<u64>,
) -> PyResult<PathBuf> {
    let opts = lidarsim::simulate::RunOptions {
        output: output.clone(),
        seed,
        profiles,
        method: None,
        tolerance: None,
        components: None,
        progress: false,
        command_line: format!("lidarsim.simulate({})", config.display()),
        shard: None,
    };
    py.allow_threads(|| lidarsim::commands::simulate(&config, &overrides, &opts, None))
        .map_err(raise)?;
    Ok(output)
}

/// The JSON of a validation report (the CLI's `--json`).
fn report_json(report: &lidarsim::validate::Report) -> lidarsim::error::Result<String> {
    serde_json::to_string(report).map_err(|e| Error::Unsupported(format!("validation report: {e}")))
}

/// `lidarsim validate CONFIG --realizations N [--seed S] --json -`: the report as JSON.
#[pyfunction]
#[pyo3(signature = (config, overrides, realizations, seed=None))]
fn validate(
    py: Python<'_>,
    config: PathBuf,
    overrides: Vec<String>,
    realizations: usize,
    seed: Option<u64>,
) -> PyResult<String> {
    py.allow_threads(|| {
        let lidar = lidarsim::scenario::Lidar::load(&config, &overrides)?;
        let opts = lidarsim::validate::ValidateOptions {
            realizations,
            method: None,
            seed,
            json: None,
        };
        report_json(&lidarsim::validate::run(&lidar, &opts)?)
    })
    .map_err(raise)
}

/// `lidarsim validate --file RAW --json -`: the file's counts against the expectation
/// it carries; the report as JSON.
#[pyfunction]
fn validate_file(py: Python<'_>, path: PathBuf) -> PyResult<String> {
    py.allow_threads(|| report_json(&lidarsim::validate::file::check_file(&path)?.0))
        .map_err(raise)
}

/// `lidarsim sweep CONFIG --vary ... --metric ... --csv CSV`: writes the CSV.
#[pyfunction]
fn sweep(
    py: Python<'_>,
    config: PathBuf,
    overrides: Vec<String>,
    vary: Vec<String>,
    metrics: Vec<String>,
    csv: PathBuf,
) -> PyResult<()> {
    py.allow_threads(|| lidarsim::commands::sweep(&config, &overrides, &vary, &metrics, &csv, None))
        .map_err(raise)
}

#[pymodule]
fn _lidarsim(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(check, m)?)?;
    m.add_function(wrap_pyfunction!(expect, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(validate, m)?)?;
    m.add_function(wrap_pyfunction!(validate_file, m)?)?;
    m.add_function(wrap_pyfunction!(sweep, m)?)?;
    Ok(())
}
