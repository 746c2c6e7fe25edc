//! The Python module `lidarsim._lidarsim` (docs/python.md): the library's commands,
//! called in the same process without the GIL, their errors raised as Python
//! exceptions with the CLI's one-line message (`ValueError` for bad input, `OSError`
//! for files). The raw file's variables come as numpy arrays that own the run's own
//! buffers (no copy); `lidarsim/__init__.py` builds the xarray Datasets from them.
//! A long call runs on a thread of its own while the calling thread waits for it
//! without the GIL and looks for Ctrl-C every 50 ms: a KeyboardInterrupt stops a
//! `simulate` before its next profile (its temporary file removed) and a `sweep` before
//! its next grid point, and is raised; a `validate` (which writes nothing) raises it at
//! once and stops in the background before its next realization; `validate_file`
//! takes no cancel flag and finishes first. The library's duration notices come as
//! `UserWarning`s, printed by nothing.

// PyO3 0.22's #[pyfunction] expansion converts each PyResult's error into itself
#![allow(clippy::useless_conversion)]

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use lidarsim::config::Method;
use lidarsim::design::sweep::{Axis, Metric};
use lidarsim::error::Error;
use lidarsim::output::raw_file::memory::{Array, MemoryFile, MemoryVariable};
use lidarsim::output::raw_file::AttrValue;
use lidarsim::scenario::{Lidar, Scenario};
use lidarsim::simulate::RunOptions;
use numpy::{IntoPyArray, PyArrayMethods};
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyUserWarning, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyList, PyTuple};

/// The CLI's error as a Python exception: files are `OSError`, the rest `ValueError`.
fn raise(e: Error) -> PyErr {
    let message = e.to_string();
    match e {
        Error::Io { .. } | Error::Output { .. } => PyOSError::new_err(message),
        _ => PyValueError::new_err(message),
    }
}

/// How often the waiting thread looks for Ctrl-C.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// Runs `work` on a thread of its own, on rayon's global pool as the CLI does, while this
/// thread waits without the GIL; a Python signal (Ctrl-C: KeyboardInterrupt) sets the
/// cancel flag `work` is given, waits for `work` to stop and is raised.
fn interruptible<T: Send>(
    py: Python<'_>,
    work: impl FnOnce(Arc<AtomicBool>) -> lidarsim::error::Result<T> + Send,
) -> PyResult<T> {
    let cancel = Arc::new(AtomicBool::new(false));
    let (done, finished) = mpsc::channel::<()>();
    let finished = Mutex::new(finished);
    std::thread::scope(|scope| {
        let flag = cancel.clone();
        let worker = scope.spawn(move || {
            let result = work(flag);
            let _ = done.send(());
            result
        });
        let mut signal = None;
        while py
            .allow_threads(|| match finished.lock() {
                Ok(f) => f.recv_timeout(SIGNAL_POLL),
                Err(_) => Err(mpsc::RecvTimeoutError::Disconnected),
            })
            .is_err_and(|e| e == mpsc::RecvTimeoutError::Timeout)
        {
            if let Err(e) = py.check_signals().and_then(|_| warn_notices(py)) {
                cancel.store(true, Ordering::SeqCst);
                signal = Some(e);
                break;
            }
        }
        let result = py.allow_threads(|| worker.join());
        let signal = signal.or_else(|| warn_notices(py).err());
        match (signal, result) {
            (Some(e), _) => Err(e),
            (None, Ok(r)) => r.map_err(raise),
            (None, Err(_)) => Err(PyRuntimeError::new_err("lidarsim: the run panicked")),
        }
    })
}

/// [`interruptible`] for work that writes nothing (`validate`): on a Python signal the
/// cancel flag is set and the signal raised at once, while the work stops in the
/// background after the realizations under way (an MPL-like realization of 150,000 shots
/// takes seconds; nothing of it is kept).
fn interruptible_detached<T: Send + 'static>(
    py: Python<'_>,
    work: impl FnOnce(Arc<AtomicBool>) -> lidarsim::error::Result<T> + Send + 'static,
) -> PyResult<T> {
    let cancel = Arc::new(AtomicBool::new(false));
    let (done, finished) = mpsc::channel::<lidarsim::error::Result<T>>();
    let finished = Mutex::new(finished);
    let flag = cancel.clone();
    std::thread::spawn(move || {
        let _ = done.send(work(flag));
    });
    loop {
        let next = py.allow_threads(|| match finished.lock() {
            Ok(f) => f.recv_timeout(SIGNAL_POLL),
            Err(_) => Err(mpsc::RecvTimeoutError::Disconnected),
        });
        match next {
            Ok(result) => {
                warn_notices(py)?;
                return result.map_err(raise);
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {
                if let Err(e) = py.check_signals().and_then(|_| warn_notices(py)) {
                    cancel.store(true, Ordering::SeqCst);
                    return Err(e);
                }
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                return Err(PyRuntimeError::new_err("lidarsim: the run panicked"));
            }
        }
    }
}

/// The library's duration notices ("expected to take about 7 min") as `UserWarning`s:
/// the module prints nothing (docs/python.md). An error where warnings are errors.
fn warn_notices(py: Python<'_>) -> PyResult<()> {
    for notice in lidarsim::resources::take_duration_notices() {
        PyErr::warn_bound(py, &py.get_type_bound::<PyUserWarning>(), &notice, 1)?;
    }
    Ok(())
}

/// A loaded and checked config: the config file, its overrides (`KEY=VALUE`, as
/// `--set`) and every channel built, loaded once for every later call.
#[pyclass(frozen, module = "lidarsim._lidarsim")]
struct Loaded {
    path: PathBuf,
    overrides: Vec<String>,
    lidar: Arc<Lidar>,
}

#[pymethods]
impl Loaded {
    #[new]
    fn new(py: Python<'_>, path: PathBuf, overrides: Vec<String>) -> PyResult<Self> {
        let lidar = py
            .allow_threads(|| Lidar::load(&path, &overrides))
            .map_err(raise)?;
        Ok(Loaded {
            path,
            overrides,
            lidar: Arc::new(lidar),
        })
    }

    /// The receiver channels' names.
    #[getter]
    fn channels(&self) -> Vec<String> {
        self.lidar.channel_names()
    }

    /// The index of the channel `name`; refused as `--channel` refuses it.
    fn channel_index(&self, name: &str) -> PyResult<usize> {
        lidarsim::commands::channel_index(&self.lidar, &self.path, name).map_err(raise)
    }
}

/// A Python attribute value tagged with its netCDF type, as the file stores it:
/// `("str" | "u64" | "i32" | "f64", value)`.
fn attr(py: Python<'_>, value: &AttrValue) -> (&'static str, PyObject) {
    match value {
        AttrValue::Str(s) => ("str", s.into_py(py)),
        AttrValue::U64(v) => ("u64", v.into_py(py)),
        AttrValue::I32(v) => ("i32", v.into_py(py)),
        AttrValue::F64(v) => ("f64", v.into_py(py)),
    }
}

fn attrs<'py>(py: Python<'py>, list: Vec<(String, AttrValue)>) -> Bound<'py, PyList> {
    let items: Vec<PyObject> = list
        .iter()
        .map(|(k, v)| (k.as_str(), attr(py, v)).into_py(py))
        .collect();
    PyList::new_bound(py, items)
}

/// A variable as `(name, dims, values, attributes)`: the values a numpy array that owns
/// the variable's buffer (moved, not copied), in its shape; strings a list.
fn variable(py: Python<'_>, v: MemoryVariable) -> PyResult<PyObject> {
    let shape = v.shape.clone();
    let values: PyObject = match v.data {
        Array::Text(t) => t.into_py(py),
        Array::I64(a) => a.into_pyarray_bound(py).reshape(shape)?.into_any().unbind(),
        Array::U16(a) => a.into_pyarray_bound(py).reshape(shape)?.into_any().unbind(),
        Array::U32(a) => a.into_pyarray_bound(py).reshape(shape)?.into_any().unbind(),
        Array::U64(a) => a.into_pyarray_bound(py).reshape(shape)?.into_any().unbind(),
        Array::F64(a) => a.into_pyarray_bound(py).reshape(shape)?.into_any().unbind(),
        Array::I32(a) => a.into_pyarray_bound(py).reshape(shape)?.into_any().unbind(),
    };
    let dims = PyTuple::new_bound(py, v.dims);
    Ok((v.name, dims, values, attrs(py, v.attributes)).into_py(py))
}

/// A raw file in memory as `(variables, root attributes)`.
fn file(py: Python<'_>, f: MemoryFile) -> PyResult<(Vec<PyObject>, Bound<'_, PyList>)> {
    let vars = f
        .variables
        .into_iter()
        .map(|v| variable(py, v))
        .collect::<PyResult<_>>()?;
    Ok((vars, attrs(py, f.root_attributes)))
}

/// `simulation.method` by name.
fn method(name: Option<&str>) -> PyResult<Option<Method>> {
    name.map(|n| match n {
        "auto" => Ok(Method::Auto),
        "shot" => Ok(Method::Shot),
        "aggregate" => Ok(Method::Aggregate),
        _ => Err(PyValueError::new_err(format!(
            "method `{n}` is not one of auto, shot, aggregate"
        ))),
    })
    .transpose()
}

/// `simulation.truth` by name (`--truth`).
fn truth_form(name: Option<&str>) -> PyResult<Option<lidarsim::config::TruthForm>> {
    use lidarsim::config::TruthForm;
    name.map(|n| match n {
        "compact" => Ok(TruthForm::Compact),
        "per-profile" => Ok(TruthForm::PerProfile),
        _ => Err(PyValueError::new_err(format!(
            "truth `{n}` is not one of compact, per-profile"
        ))),
    })
    .transpose()
}

/// The options of a run, as the CLI's `simulate` sets them.
#[allow(clippy::too_many_arguments)]
fn run_options(
    loaded: &Loaded,
    output: PathBuf,
    profiles: Option<usize>,
    seed: Option<u64>,
    method_name: Option<&str>,
    truth: Option<&str>,
    progress: bool,
) -> PyResult<RunOptions> {
    Ok(RunOptions {
        output,
        seed,
        profiles,
        method: method(method_name)?,
        truth: truth_form(truth)?,
        progress,
        command_line: format!("lidarsim.simulate({})", loaded.path.display()),
        ..RunOptions::default()
    })
}

/// `lidarsim expect`, every channel: [`lidarsim::output::expect::model_variables`]
/// (the raw file's variables before its first profile, the CSV's two S/N) and the
/// CSV's shots per profile.
#[pyfunction]
fn expect<'py>(
    py: Python<'py>,
    loaded: &Loaded,
) -> PyResult<(Vec<PyObject>, Bound<'py, PyList>, f64)> {
    let (fixed, shots) = py
        .allow_threads(|| {
            let call = format!("lidarsim.expect({})", loaded.path.display());
            lidarsim::output::expect::model_variables(&loaded.lidar, &call)
        })
        .map_err(raise)?;
    let vars: Vec<PyObject> = fixed
        .into_iter()
        .map(|v| variable(py, v))
        .collect::<PyResult<_>>()?;
    Ok((vars, attrs(py, Vec::new()), shots))
}

/// `lidarsim simulate CONFIG -o OUTPUT`: writes the raw file exactly as the CLI does
/// (same seed, same counts and truth; the `history` attribute names this call);
/// returns the run's warning, if any.
#[pyfunction]
#[pyo3(signature = (loaded, output, profiles=None, seed=None, method=None, truth=None, progress=false, photons=None))]
#[allow(clippy::too_many_arguments)]
fn simulate(
    py: Python<'_>,
    loaded: &Loaded,
    output: PathBuf,
    profiles: Option<usize>,
    seed: Option<u64>,
    method: Option<&str>,
    truth: Option<&str>,
    progress: bool,
    photons: Option<PathBuf>,
) -> PyResult<Option<String>> {
    let opts = run_options(loaded, output, profiles, seed, method, truth, progress)?;
    let summary = interruptible(py, |cancel| {
        let opts = RunOptions {
            cancel: Some(cancel),
            photons,
            ..opts
        };
        lidarsim::commands::simulate_quietly(
            &loaded.path,
            &loaded.overrides,
            &opts,
            None,
            lidarsim::commands::OutputFormat::Raw,
        )
    })?;
    Ok(summary.warning)
}

/// An in-memory run: variables, root attributes, warning, (drawing, whole) times in s.
type InMemory<'py> = (
    Vec<PyObject>,
    Bound<'py, PyList>,
    Option<String>,
    (f64, f64),
);

/// `lidarsim simulate` kept in memory: the raw file's variables and root attributes,
/// the same counts and truth as the file for the same seed, the run's warning, and its
/// drawing and whole times (s).
#[pyfunction]
#[pyo3(signature = (loaded, profiles=None, seed=None, method=None, truth=None, progress=false))]
fn simulate_in_memory<'py>(
    py: Python<'py>,
    loaded: &Loaded,
    profiles: Option<usize>,
    seed: Option<u64>,
    method: Option<&str>,
    truth: Option<&str>,
    progress: bool,
) -> PyResult<InMemory<'py>> {
    let opts = run_options(
        loaded,
        PathBuf::new(),
        profiles,
        seed,
        method,
        truth,
        progress,
    )?;
    let (memory, summary) = interruptible(py, |cancel| {
        let opts = RunOptions {
            cancel: Some(cancel),
            ..opts
        };
        lidarsim::simulate::run_in_memory(&loaded.lidar, &opts)
    })?;
    let (vars, root) = file(py, memory)?;
    let times = (summary.drawing.as_secs_f64(), summary.elapsed.as_secs_f64());
    Ok((vars, root, summary.warning, times))
}

/// The JSON of a validation report (the CLI's `--json`).
fn report_json(report: &lidarsim::validate::Report) -> lidarsim::error::Result<String> {
    serde_json::to_string(report).map_err(|e| Error::Unsupported(format!("validation report: {e}")))
}

/// `lidarsim validate CONFIG --realizations N [--seed S] --json -`: the report as JSON.
#[pyfunction]
#[pyo3(signature = (loaded, realizations, seed=None))]
fn validate(
    py: Python<'_>,
    loaded: &Loaded,
    realizations: usize,
    seed: Option<u64>,
) -> PyResult<String> {
    let lidar = loaded.lidar.clone();
    interruptible_detached(py, move |cancel| {
        let opts = lidarsim::validate::ValidateOptions {
            realizations,
            method: None,
            seed,
            json: None,
        };
        report_json(&lidarsim::validate::run_cancellable(
            &lidar, &opts, &cancel,
        )?)
    })
}

/// `lidarsim validate --file RAW --json -`: the file's counts against the expectation
/// it carries; the report as JSON.
#[pyfunction]
fn validate_file(py: Python<'_>, path: PathBuf) -> PyResult<String> {
    interruptible(py, |_| {
        report_json(&lidarsim::validate::file::check_file(&path)?.0)
    })
}

/// A varied key's values: the CLI's range (`"0.01..1:log:5"`) or a list of numbers.
#[derive(FromPyObject)]
enum Values {
    Range(String),
    List(Vec<f64>),
}

/// The sweep's axes: a range as `--vary KEY=RANGE` parses it; a list as given (finite,
/// at least one value), refused in one line naming the key.
fn axes(vary: Vec<(String, Values)>) -> lidarsim::error::Result<Vec<Axis>> {
    vary.into_iter()
        .map(|(key, values)| match values {
            Values::Range(range) => Axis::parse(&format!("{key}={range}")),
            Values::List(values) if values.is_empty() => Err(Error::Unsupported(format!(
                "vary {key}: an empty list of values"
            ))),
            Values::List(values) => match values.iter().find(|v| !v.is_finite()) {
                Some(v) => Err(Error::Unsupported(format!(
                    "vary {key}: {v} is not a finite number"
                ))),
                None => Ok(Axis { key, values }),
            },
        })
        .collect()
}

/// The scenario of one channel of the config with `overrides`: with `channel`, that
/// channel of the whole lidar; without, the config's only channel (a multi-channel
/// config asks for `channel`, naming its channels).
fn sweep_scenario(
    config: &Path,
    overrides: &[String],
    channel: Option<&str>,
) -> lidarsim::error::Result<Scenario> {
    let mut lidar = Lidar::load(config, overrides)?;
    let k = match channel {
        Some(name) => lidarsim::commands::channel_index(&lidar, config, name)?,
        None if lidar.channels.len() == 1 => 0,
        None => {
            return Err(Error::config(
                config.display().to_string(),
                "instrument.channels",
                format!(
                    "lists {} channels: pass channel= one of {}",
                    lidar.channels.len(),
                    lidar.channel_names().join(", ")
                ),
            ))
        }
    };
    Ok(lidar.channels.swap_remove(k))
}

/// `lidarsim sweep CONFIG --vary ... --metric ...`: the metrics of one channel at every
/// grid point, as `(axes' keys and values, rows of (point, metrics))`: the numbers of
/// the CLI's CSV (`sweep::run` on the same scenarios), `vary` a list of `(key, range
/// or list of values)`.
#[pyfunction]
#[pyo3(signature = (loaded, vary, metrics, channel=None))]
fn sweep(
    py: Python<'_>,
    loaded: &Loaded,
    vary: Vec<(String, Values)>,
    metrics: Vec<String>,
    channel: Option<String>,
) -> PyResult<SweepTable> {
    interruptible(py, |cancel| {
        let (config, overrides) = (loaded.path.as_path(), &loaded.overrides);
        let axes = axes(vary)?;
        let parsed = Metric::parse_all(&metrics)?;
        let base = sweep_scenario(config, overrides, channel.as_deref())?;
        let points = lidarsim::design::sweep::grid(&axes)?.len();
        let at_once = points.min(rayon::current_num_threads().max(1)) as f64;
        lidarsim::resources::require_memory(
            &format!("sweeping {points} points of {} bins", base.geometry.n_bins),
            at_once
                * lidarsim::scenario::model_bytes(
                    base.geometry.n_bins as f64,
                    base.path.laid_bytes(),
                ),
        )?;
        let scenario = |extra: &[String]| {
            let all: Vec<String> = overrides.iter().chain(extra).cloned().collect();
            sweep_scenario(config, &all, channel.as_deref())
        };
        let rows = lidarsim::design::sweep::run(&axes, &parsed, &scenario, &|| {}, &cancel)?;
        let axes = axes.into_iter().map(|a| (a.key, a.values)).collect();
        Ok((axes, rows))
    })
}

/// A sweep's axes `(key, values)` and rows `(point, metrics)`.
type SweepTable = (Vec<(String, Vec<f64>)>, Vec<(Vec<f64>, Vec<f64>)>);

/// A whole-number argument parsed as the CLI parses its option of that name
/// (`profiles`, `realizations`, `seed`: [`lidarsim::cli_values`]), refused with the
/// CLI's range.
#[pyfunction]
fn whole_option(name: &str, value: &str) -> PyResult<u64> {
    use lidarsim::cli_values;
    let parsed = match name {
        "profiles" => cli_values::profiles(value).map(|n| n as u64),
        "realizations" => cli_values::realizations(value).map(|n| n as u64),
        "seed" => cli_values::seed(value),
        _ => Err("is not an option of lidarsim's (profiles, realizations, seed)".to_string()),
    };
    parsed.map_err(|why| PyValueError::new_err(format!("{name} = {value}: {why}")))
}

#[pymodule]
fn _lidarsim(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // a library prints nothing: its duration notices become warnings (warn_notices)
    lidarsim::resources::keep_duration_notices();
    // the lidarsim crate's version (build.rs reads it from its Cargo.toml)
    m.add("__version__", env!("LIDARSIM_VERSION"))?;
    m.add_class::<Loaded>()?;
    m.add_function(wrap_pyfunction!(expect, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(simulate_in_memory, m)?)?;
    m.add_function(wrap_pyfunction!(validate, m)?)?;
    m.add_function(wrap_pyfunction!(validate_file, m)?)?;
    m.add_function(wrap_pyfunction!(sweep, m)?)?;
    m.add_function(wrap_pyfunction!(whole_option, m)?)?;
    Ok(())
}
