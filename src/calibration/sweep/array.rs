//! `--shard auto`: which part (I of N) of a sweep this task of a scheduler's job array runs,
//! read from the array runner's environment.
//!
//! Understood, where the runner exports both the task's index and the number of tasks:
//! - Slurm (`sbatch --array=…`): `SLURM_ARRAY_TASK_ID`, `SLURM_ARRAY_TASK_COUNT`,
//!   `SLURM_ARRAY_TASK_MIN` and, if set, `SLURM_ARRAY_TASK_STEP` / `SLURM_ARRAY_TASK_MAX`.
//!   Task ids follow the `--array` range (0-2, 1-3, 0-8:4 …), so I = (ID − MIN) / STEP + 1;
//!   an irregular list such as `--array=1,3,4` has no such mapping and is refused.
//! - Grid Engine (`qsub -t FIRST-LAST:STEP`): `SGE_TASK_ID`, `SGE_TASK_FIRST`,
//!   `SGE_TASK_LAST`, `SGE_TASK_STEPSIZE`.
//! - AWS Batch array jobs: `AWS_BATCH_JOB_ARRAY_INDEX` (from 0), `AWS_BATCH_JOB_ARRAY_SIZE`.
//!
//! PBS (`PBS_ARRAY_INDEX`, `PBS_ARRAYID`) and LSF (`LSB_JOBINDEX`) export the index but not
//! the number of tasks, so `--shard auto` refuses them with a hint to pass `--shard I/N`.

use crate::error::{Error, Result};

/// The job-array runners whose environment `--shard auto` reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Runner {
    Slurm,
    GridEngine,
    AwsBatch,
}

impl Runner {
    /// The variable whose presence says that this runner started the task.
    fn marker(self) -> &'static str {
        match self {
            Runner::Slurm => "SLURM_ARRAY_TASK_ID",
            Runner::GridEngine => "SGE_TASK_ID",
            Runner::AwsBatch => "AWS_BATCH_JOB_ARRAY_INDEX",
        }
    }
}

/// Runners that export an index but no task count: (variable, runner name).
const INDEX_ONLY: [(&str, &str); 3] = [
    ("PBS_ARRAY_INDEX", "PBS Pro"),
    ("PBS_ARRAYID", "Torque/PBS"),
    ("LSB_JOBINDEX", "LSF"),
];

/// The shard (I, N), 1 ≤ I ≤ N, of this job-array task, from the environment as seen through
/// `get` (a variable's value, `None` when unset). Exactly one runner's variables must be
/// present; anything missing, unparsable or inconsistent is a one-line error naming the
/// variables.
pub fn shard_from_env(get: &dyn Fn(&str) -> Option<String>) -> Result<(usize, usize)> {
    // Grid Engine sets SGE_TASK_ID=undefined and LSF sets LSB_JOBINDEX=0 outside arrays.
    let present = |name: &str| {
        get(name).is_some_and(|v| {
            let v = v.trim();
            !v.is_empty() && v != "undefined" && !(name == "LSB_JOBINDEX" && v == "0")
        })
    };
    let found: Vec<Runner> = [Runner::Slurm, Runner::GridEngine, Runner::AwsBatch]
        .into_iter()
        .filter(|r| present(r.marker()))
        .collect();
    match found.as_slice() {
        [] => {
            if let Some((var, name)) = INDEX_ONLY.iter().find(|(v, _)| present(v)) {
                return Err(invalid(format!(
                    "{name} sets {var} but no number of tasks; pass --shard I/N (I = the task's position from 1, N = the number of tasks)"
                )));
            }
            Err(invalid(
                "no job-array task found (SLURM_ARRAY_TASK_ID, SGE_TASK_ID or AWS_BATCH_JOB_ARRAY_INDEX is not set); run it as a task of a job array or pass --shard I/N".to_string(),
            ))
        }
        [one] => {
            let num = |name: &str| -> Result<Option<i64>> {
                match get(name) {
                    None => Ok(None),
                    Some(v) => v
                        .trim()
                        .parse::<i64>()
                        .map(Some)
                        .map_err(|_| invalid(format!("{name} = '{v}' is not an integer"))),
                }
            };
            let need = |name: &str| -> Result<i64> {
                num(name)?
                    .ok_or_else(|| invalid(format!("{} is set but {name} is not", one.marker())))
            };
            match one {
                Runner::Slurm => {
                    let id = need("SLURM_ARRAY_TASK_ID")?;
                    let count = need("SLURM_ARRAY_TASK_COUNT")?;
                    let min = need("SLURM_ARRAY_TASK_MIN")?;
                    let step = num("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1);
                    let max = num("SLURM_ARRAY_TASK_MAX")?;
                    regular("SLURM_ARRAY_TASK_", id, min, step, count, max)
                }
                Runner::GridEngine => {
                    let id = need("SGE_TASK_ID")?;
                    let first = need("SGE_TASK_FIRST")?;
                    let last = need("SGE_TASK_LAST")?;
                    let step = num("SGE_TASK_STEPSIZE")?.unwrap_or(1);
                    if step < 1 || last < first {
                        return Err(invalid(format!(
                            "SGE_TASK_FIRST = {first}, SGE_TASK_LAST = {last}, SGE_TASK_STEPSIZE = {step} do not describe a task range"
                        )));
                    }
                    let count = (last - first) / step + 1;
                    regular("SGE_TASK_", id, first, step, count, None)
                }
                Runner::AwsBatch => {
                    let id = need("AWS_BATCH_JOB_ARRAY_INDEX")?;
                    let size = need("AWS_BATCH_JOB_ARRAY_SIZE")?;
                    regular("AWS_BATCH_JOB_ARRAY_", id, 0, 1, size, None)
                }
            }
        }
        several => Err(invalid(format!(
            "the variables of several job-array runners are set ({}); pass --shard I/N",
            several
                .iter()
                .map(|r| r.marker())
                .collect::<Vec<_>>()
                .join(", ")
        ))),
    }
}

/// I = (id − min) / step + 1 for a regular range of `count` tasks from `min` (ending at `max`
/// where the runner says).
fn regular(
    prefix: &str,
    id: i64,
    min: i64,
    step: i64,
    count: i64,
    max: Option<i64>,
) -> Result<(usize, usize)> {
    let what = || {
        format!(
            "task id {id} in a range from {min} with step {step}, {count} tasks{}",
            max.map(|m| format!(", last {m}")).unwrap_or_default()
        )
    };
    if count < 1 || step < 1 {
        return Err(invalid(format!(
            "{prefix}*: {} is not a task range",
            what()
        )));
    }
    if let Some(max) = max {
        if min + (count - 1) * step != max {
            return Err(invalid(format!(
                "{prefix}*: {}: the array's ids are not a regular range (e.g. --array=1,3,4); submit a range such as --array=1-{count}",
                what()
            )));
        }
    }
    let offset = id - min;
    if offset < 0 || offset % step != 0 || offset / step >= count {
        return Err(invalid(format!(
            "{prefix}*: {}: the id is not one of the range's",
            what()
        )));
    }
    Ok(((offset / step + 1) as usize, count as usize))
}

fn invalid(message: String) -> Error {
    Error::Invalid(format!("--shard auto: {message}"))
}

/// [`shard_from_env`] on the process's environment.
pub fn shard_from_process_env() -> Result<(usize, usize)> {
    shard_from_env(&|name| std::env::var(name).ok())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(vars: &[(&str, &str)]) -> Result<(usize, usize)> {
        let vars: Vec<(String, String)> = vars
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        shard_from_env(&move |name| vars.iter().find(|(k, _)| k == name).map(|(_, v)| v.clone()))
    }

    fn slurm(
        id: &str,
        min: &str,
        max: &str,
        step: &str,
        count: &str,
    ) -> Vec<(&'static str, String)> {
        vec![
            ("SLURM_ARRAY_TASK_ID", id.into()),
            ("SLURM_ARRAY_TASK_MIN", min.into()),
            ("SLURM_ARRAY_TASK_MAX", max.into()),
            ("SLURM_ARRAY_TASK_STEP", step.into()),
            ("SLURM_ARRAY_TASK_COUNT", count.into()),
        ]
    }

    #[test]
    fn shard_table() {
        // (environment, expected (I, N) or a piece of the error message)
        type Case = (
            Vec<(&'static str, String)>,
            std::result::Result<(usize, usize), &'static str>,
        );
        let owned = |v: &[(&'static str, &str)]| -> Vec<(&'static str, String)> {
            v.iter().map(|(k, x)| (*k, x.to_string())).collect()
        };
        let cases: Vec<Case> = vec![
            // Slurm, as the one-node cluster exported them (scripts/slurm/run-local.sh).
            (slurm("1", "1", "3", "1", "3"), Ok((1, 3))),
            (slurm("3", "1", "3", "1", "3"), Ok((3, 3))),
            (slurm("0", "0", "2", "1", "3"), Ok((1, 3))),
            (slurm("2", "0", "2", "1", "3"), Ok((3, 3))),
            (slurm("2", "0", "4", "2", "3"), Ok((2, 3))), // --array=0-4:2
            (slurm("7", "7", "7", "1", "1"), Ok((1, 1))),
            // --array=1,3,4 (Slurm says MIN 1, MAX 4, STEP 1, COUNT 3): no regular mapping.
            (slurm("3", "1", "4", "1", "3"), Err("not a regular range")),
            (
                slurm("4", "1", "3", "1", "3"),
                Err("not one of the range's"),
            ),
            (
                slurm("0", "1", "3", "1", "3"),
                Err("not one of the range's"),
            ),
            (
                slurm("1", "0", "4", "2", "3"),
                Err("not one of the range's"),
            ),
            (
                slurm("1", "1", "3", "1", "x"),
                Err("SLURM_ARRAY_TASK_COUNT = 'x' is not an integer"),
            ),
            (slurm("1", "1", "0", "1", "0"), Err("not a task range")),
            // Without MAX and STEP (older Slurm): MIN and COUNT suffice.
            (
                owned(&[
                    ("SLURM_ARRAY_TASK_ID", "5"),
                    ("SLURM_ARRAY_TASK_MIN", "4"),
                    ("SLURM_ARRAY_TASK_COUNT", "2"),
                ]),
                Ok((2, 2)),
            ),
            (
                owned(&[
                    ("SLURM_ARRAY_TASK_ID", "1"),
                    ("SLURM_ARRAY_TASK_COUNT", "3"),
                ]),
                Err("SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_MIN is not"),
            ),
            (
                owned(&[("SLURM_ARRAY_TASK_ID", "1"), ("SLURM_ARRAY_TASK_MIN", "1")]),
                Err("SLURM_ARRAY_TASK_COUNT is not"),
            ),
            // A plain Slurm job (no array) has SLURM_JOB_ID only.
            (
                owned(&[("SLURM_JOB_ID", "12")]),
                Err("no job-array task found"),
            ),
            (vec![], Err("no job-array task found")),
            // Grid Engine.
            (
                owned(&[
                    ("SGE_TASK_ID", "3"),
                    ("SGE_TASK_FIRST", "1"),
                    ("SGE_TASK_LAST", "4"),
                    ("SGE_TASK_STEPSIZE", "1"),
                ]),
                Ok((3, 4)),
            ),
            (
                owned(&[
                    ("SGE_TASK_ID", "21"),
                    ("SGE_TASK_FIRST", "1"),
                    ("SGE_TASK_LAST", "21"),
                    ("SGE_TASK_STEPSIZE", "10"),
                ]),
                Ok((3, 3)),
            ),
            (
                owned(&[
                    ("SGE_TASK_ID", "undefined"),
                    ("SGE_TASK_FIRST", "undefined"),
                ]),
                Err("no job-array task found"),
            ),
            (owned(&[("SGE_TASK_ID", "2")]), Err("SGE_TASK_FIRST is not")),
            // AWS Batch: index from 0.
            (
                owned(&[
                    ("AWS_BATCH_JOB_ARRAY_INDEX", "0"),
                    ("AWS_BATCH_JOB_ARRAY_SIZE", "4"),
                ]),
                Ok((1, 4)),
            ),
            (
                owned(&[
                    ("AWS_BATCH_JOB_ARRAY_INDEX", "4"),
                    ("AWS_BATCH_JOB_ARRAY_SIZE", "4"),
                ]),
                Err("not one of the range's"),
            ),
            // Index without count.
            (
                owned(&[("PBS_ARRAY_INDEX", "2")]),
                Err("PBS Pro sets PBS_ARRAY_INDEX but no number of tasks"),
            ),
            (
                owned(&[("LSB_JOBINDEX", "2")]),
                Err("LSF sets LSB_JOBINDEX"),
            ),
            (
                owned(&[("LSB_JOBINDEX", "0")]),
                Err("no job-array task found"),
            ),
            // Two runners at once.
            (
                {
                    let mut v = slurm("1", "1", "3", "1", "3");
                    v.push(("SGE_TASK_ID", "1".into()));
                    v
                },
                Err("several job-array runners"),
            ),
        ];
        for (env, want) in cases {
            let vars: Vec<(&str, &str)> = env.iter().map(|(k, v)| (*k, v.as_str())).collect();
            let got = run(&vars);
            match (&got, want) {
                (Ok(g), Ok(w)) => assert_eq!(*g, w, "{env:?}"),
                (Err(e), Err(piece)) => {
                    let msg = e.to_string();
                    assert!(msg.starts_with("--shard auto: "), "{msg}");
                    assert!(msg.contains(piece), "{env:?}: '{msg}' lacks '{piece}'");
                    assert!(!msg.contains('\n'), "one line: {msg}");
                }
                _ => panic!("{env:?}: got {got:?}, want {want:?}"),
            }
        }
    }
}
