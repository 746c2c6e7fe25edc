//! `--shard auto`: the shard of this process from the environment an array-job engine
//! gives each of its tasks (docs/scale.md lists them).
//!
//! | engine | index | count |
//! |---|---|---|
//! | Slurm job array (`sbatch --array=A-B[:S]`) | `(SLURM_ARRAY_TASK_ID − SLURM_ARRAY_TASK_MIN) / SLURM_ARRAY_TASK_STEP` | `SLURM_ARRAY_TASK_COUNT` |
//! | Kubernetes indexed Job (`completionMode: Indexed`) | `JOB_COMPLETION_INDEX` | `LIDARSIM_SHARD_COUNT` (the Job's `completions`, set in the pod's `env`) |
//! | AWS Batch array job | `AWS_BATCH_JOB_ARRAY_INDEX` | `LIDARSIM_SHARD_COUNT` (the array size) |
//!
//! Slurm first; a Slurm array need not start at 0 (`--array=1-8`), so its index counts
//! from `SLURM_ARRAY_TASK_MIN`, in steps of `SLURM_ARRAY_TASK_STEP` (1 when unset).

use super::cut::Shard;
use crate::error::{Error, Result};

/// Slurm's array task id.
pub const SLURM_ID: &str = "SLURM_ARRAY_TASK_ID";
/// Slurm's number of tasks in the array.
pub const SLURM_COUNT: &str = "SLURM_ARRAY_TASK_COUNT";
/// Slurm's lowest task id of the array.
pub const SLURM_MIN: &str = "SLURM_ARRAY_TASK_MIN";
/// Slurm's step between task ids.
pub const SLURM_STEP: &str = "SLURM_ARRAY_TASK_STEP";
/// The index of a Kubernetes indexed Job's pod.
pub const K8S_INDEX: &str = "JOB_COMPLETION_INDEX";
/// The index of an AWS Batch array job's child.
pub const AWS_INDEX: &str = "AWS_BATCH_JOB_ARRAY_INDEX";
/// The shard count where the engine does not give it (Kubernetes, AWS Batch).
pub const COUNT: &str = "LIDARSIM_SHARD_COUNT";

/// The shard of a process whose environment `var` reads; a one-line error naming the
/// variables looked for, or the one whose value is wrong.
pub fn from_environment(var: impl Fn(&str) -> Option<String>) -> Result<Shard> {
    let number = |name: &str| -> Result<Option<usize>> {
        var(name)
            .map(|v| {
                v.trim().parse::<usize>().map_err(|_| {
                    Error::Unsupported(format!("--shard auto: {name}={v:?} is not a whole number"))
                })
            })
            .transpose()
    };
    let required = |name: &str, with: &str| -> Result<usize> {
        number(name)?.ok_or_else(|| {
            Error::Unsupported(format!(
                "--shard auto: {with} is set but {name} is not; it gives the shard count"
            ))
        })
    };
    let shard = |index: usize, count: usize, from: String| {
        Shard::new(index, count)
            .map_err(|why| Error::Unsupported(format!("--shard auto: {from}: {why}")))
    };
    if let Some(id) = number(SLURM_ID)? {
        let count = required(SLURM_COUNT, SLURM_ID)?;
        let min = number(SLURM_MIN)?.unwrap_or(0);
        let step = number(SLURM_STEP)?.unwrap_or(1);
        if step == 0 {
            return Err(Error::Unsupported(format!(
                "--shard auto: {SLURM_STEP}=0: the step between task ids must be a whole \
                 number of at least 1 (sbatch --array=A-B:S, S ≥ 1)"
            )));
        }
        let from = format!(
            "{SLURM_ID}={id}, {SLURM_MIN}={min}, {SLURM_STEP}={step}, {SLURM_COUNT}={count}"
        );
        if id < min || (id - min) % step != 0 {
            return Err(Error::Unsupported(format!(
                "--shard auto: {from}: the task id is not {SLURM_MIN} + k·{SLURM_STEP} \
                 (k = 0 to {SLURM_COUNT} − 1); submit with --array=0-{}",
                count.saturating_sub(1)
            )));
        }
        return shard((id - min) / step, count, from);
    }
    for index_var in [K8S_INDEX, AWS_INDEX] {
        if let Some(index) = number(index_var)? {
            let count = required(COUNT, index_var)?;
            return shard(
                index,
                count,
                format!("{index_var}={index}, {COUNT}={count}"),
            );
        }
    }
    Err(Error::Unsupported(format!(
        "--shard auto: no array-job index in the environment (looked for {SLURM_ID} with \
         {SLURM_COUNT}, {K8S_INDEX} or {AWS_INDEX} with {COUNT}); give --shard K/N"
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(vars: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |name| {
            vars.iter()
                .find(|(k, _)| *k == name)
                .map(|(_, v)| v.to_string())
        }
    }

    #[test]
    fn slurm_arrays_count_from_their_first_task() {
        let s = from_environment(env(&[
            (SLURM_ID, "3"),
            (SLURM_COUNT, "4"),
            (SLURM_MIN, "1"),
        ]))
        .unwrap();
        assert_eq!(s, Shard { index: 2, count: 4 });
        let s = from_environment(env(&[
            (SLURM_ID, "6"),
            (SLURM_COUNT, "4"),
            (SLURM_MIN, "0"),
            (SLURM_STEP, "2"),
        ]))
        .unwrap();
        assert_eq!(s, Shard { index: 3, count: 4 });
    }

    #[test]
    fn kubernetes_takes_its_count_from_lidarsim_shard_count() {
        let s = from_environment(env(&[(K8S_INDEX, "0"), (COUNT, "8")])).unwrap();
        assert_eq!(s, Shard { index: 0, count: 8 });
        let e = from_environment(env(&[(K8S_INDEX, "0")])).unwrap_err();
        assert!(e.to_string().contains("LIDARSIM_SHARD_COUNT is not"), "{e}");
    }

    #[test]
    fn a_missing_or_wrong_environment_is_named() {
        let e = from_environment(env(&[])).unwrap_err().to_string();
        for name in [SLURM_ID, SLURM_COUNT, K8S_INDEX, AWS_INDEX, COUNT] {
            assert!(e.contains(name), "{e}");
        }
        let e = from_environment(env(&[(SLURM_ID, "x"), (SLURM_COUNT, "4")])).unwrap_err();
        assert!(e.to_string().contains("SLURM_ARRAY_TASK_ID=\"x\""), "{e}");
        let e = from_environment(env(&[(SLURM_ID, "5"), (SLURM_COUNT, "4")])).unwrap_err();
        assert!(e.to_string().contains("0 to N-1"), "{e}");
        let e = from_environment(env(&[
            (SLURM_ID, "0"),
            (SLURM_COUNT, "4"),
            (SLURM_STEP, "0"),
        ]))
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("SLURM_ARRAY_TASK_STEP=0") && e.contains("at least 1"),
            "{e}"
        );
        let e = from_environment(env(&[
            (SLURM_ID, "0"),
            (SLURM_COUNT, "4"),
            (SLURM_STEP, "-2"),
        ]))
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("SLURM_ARRAY_TASK_STEP=\"-2\" is not a whole number"),
            "{e}"
        );
        let e = from_environment(env(&[
            (SLURM_ID, "4"),
            (SLURM_COUNT, "4"),
            (SLURM_MIN, "1"),
            (SLURM_STEP, "2"),
        ]))
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("not SLURM_ARRAY_TASK_MIN + k·SLURM_ARRAY_TASK_STEP"),
            "{e}"
        );
    }
}
