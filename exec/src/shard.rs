//! Shards: one run's trials split over several processes (a Slurm job array, a Kubernetes
//! Indexed Job, CI jobs), each running a contiguous block of them.
//!
//! Trial i of a run seeded S always uses seed S + i, whichever process runs it, so shard I of
//! N runs exactly the trials, layouts and outcomes a single run gives for its block, and
//! [`crate::merge`] joins the shards' reports into the single run's report.

use serde::{Deserialize, Serialize};
use std::fmt;
use std::ops::Range;
use std::str::FromStr;

/// Shard `index` of `count` (numbered from 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// Which shard, from 0 to `count - 1`.
    pub index: usize,
    /// How many shards the run is split into.
    pub count: usize,
}

/// Why a shard cannot be chosen.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ShardError {
    /// The text is not `I/N`, `auto` or `auto/N`.
    #[error("`{0}` is not a shard: expected I/N (shard I of N, from 0), `auto` or `auto/N`")]
    Syntax(String),
    /// No shards, or an index at or past the count.
    #[error("shard {index}/{count}: shards are numbered 0 to N-1 and N is at least 1")]
    OutOfRange {
        /// The index given.
        index: usize,
        /// The count given.
        count: usize,
    },
    /// `auto` outside a job array.
    #[error(
        "--shard auto: neither SLURM_ARRAY_TASK_ID (a Slurm job array, sbatch --array) nor \
         JOB_COMPLETION_INDEX (a Kubernetes Indexed Job) is set; give the shard as I/N"
    )]
    NoScheduler,
    /// A Kubernetes Indexed Job does not tell its pods the number of completions.
    #[error(
        "--shard auto: JOB_COMPLETION_INDEX is {index} but the number of shards is not known: \
         give it as --shard auto/N (N the Job's completions)"
    )]
    CountMissing {
        /// The pod's index.
        index: usize,
    },
    /// An environment variable that is not a whole number.
    #[error("--shard auto: {var} is `{value}`, not a whole number")]
    Variable {
        /// The variable.
        var: &'static str,
        /// Its value.
        value: String,
    },
    /// `auto/N` inside a Slurm array of another size.
    #[error("--shard auto/{given}: the Slurm array has {found} tasks (SLURM_ARRAY_TASK_COUNT)")]
    CountMismatch {
        /// The count given.
        given: usize,
        /// The array's.
        found: usize,
    },
    /// More shards than trials: some shard would run none.
    #[error("shard {index}/{count} of a run of {trials} trial(s) holds no trial: use at most {trials} shard(s)")]
    Empty {
        /// The shard's index.
        index: usize,
        /// The shards.
        count: usize,
        /// The run's trials.
        trials: usize,
    },
}

impl Shard {
    /// Shard `index` of `count`, checked.
    pub fn new(index: usize, count: usize) -> Result<Shard, ShardError> {
        if count == 0 || index >= count {
            return Err(ShardError::OutOfRange { index, count });
        }
        Ok(Shard { index, count })
    }

    /// The trials of a run of `total` that this shard runs: the `index`-th of `count`
    /// contiguous blocks whose sizes differ by at most one.
    pub fn trials(&self, total: usize) -> Range<usize> {
        (self.index * total / self.count)..((self.index + 1) * total / self.count)
    }

    /// [`Shard::trials`], refused when the block is empty (more shards than trials).
    pub fn nonempty_trials(&self, total: usize) -> Result<Range<usize>, ShardError> {
        let range = self.trials(total);
        if range.is_empty() {
            return Err(ShardError::Empty {
                index: self.index,
                count: self.count,
                trials: total,
            });
        }
        Ok(range)
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// What `--shard` asks for: a given shard, or the one the scheduler's environment names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShardRequest {
    /// `I/N`.
    Given(Shard),
    /// `auto` (count from Slurm) or `auto/N` (count given, as a Kubernetes Indexed Job needs).
    Auto(Option<usize>),
}

impl FromStr for ShardRequest {
    type Err = ShardError;

    fn from_str(text: &str) -> Result<ShardRequest, ShardError> {
        let syntax = || ShardError::Syntax(text.to_string());
        let number = |s: &str| s.trim().parse::<usize>().map_err(|_| syntax());
        match text.trim().split_once('/') {
            None if text.trim() == "auto" => Ok(ShardRequest::Auto(None)),
            None => Err(syntax()),
            Some(("auto", n)) => {
                let count = number(n)?;
                if count == 0 {
                    return Err(ShardError::OutOfRange { index: 0, count });
                }
                Ok(ShardRequest::Auto(Some(count)))
            }
            Some((i, n)) => Ok(ShardRequest::Given(Shard::new(number(i)?, number(n)?)?)),
        }
    }
}

impl ShardRequest {
    /// The shard asked for, reading the scheduler's variables through `var` for `auto`:
    /// Slurm's `SLURM_ARRAY_TASK_ID` and `SLURM_ARRAY_TASK_COUNT` (the index counted from
    /// `SLURM_ARRAY_TASK_MIN` in steps of `SLURM_ARRAY_TASK_STEP`, so `--array=1-4` and
    /// `--array=0-6:2` work too), else a Kubernetes Indexed Job's `JOB_COMPLETION_INDEX` with
    /// the count given as `auto/N`.
    pub fn resolve(&self, var: impl Fn(&str) -> Option<String>) -> Result<Shard, ShardError> {
        let count = match *self {
            ShardRequest::Given(shard) => return Ok(shard),
            ShardRequest::Auto(count) => count,
        };
        let number = |name: &'static str| -> Result<Option<usize>, ShardError> {
            match var(name) {
                None => Ok(None),
                Some(value) => value
                    .trim()
                    .parse::<usize>()
                    .map(Some)
                    .map_err(|_| ShardError::Variable { var: name, value }),
            }
        };
        if let Some(id) = number("SLURM_ARRAY_TASK_ID")? {
            let min = number("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
            let step = number("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1).max(1);
            let found = number("SLURM_ARRAY_TASK_COUNT")?;
            let index = id.saturating_sub(min) / step;
            let total = match (count, found) {
                (Some(given), Some(found)) if given != found => {
                    return Err(ShardError::CountMismatch { given, found })
                }
                (_, Some(n)) | (Some(n), None) => n,
                (None, None) => return Err(ShardError::CountMissing { index }),
            };
            return Shard::new(index, total);
        }
        if let Some(index) = number("JOB_COMPLETION_INDEX")? {
            let count = count.ok_or(ShardError::CountMissing { index })?;
            return Shard::new(index, count);
        }
        Err(ShardError::NoScheduler)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    fn env(vars: &[(&str, &str)]) -> impl Fn(&str) -> Option<String> {
        let map: HashMap<String, String> = vars
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        move |k| map.get(k).cloned()
    }

    #[test]
    fn shards_split_the_trials_into_contiguous_blocks_covering_each_once() {
        for (total, count) in [(120, 3), (400, 4), (10, 3), (7, 7), (1000, 9)] {
            let mut next = 0;
            for index in 0..count {
                let r = Shard::new(index, count).unwrap().trials(total);
                assert_eq!(r.start, next);
                assert!(r.len() == total / count || r.len() == total / count + 1);
                next = r.end;
            }
            assert_eq!(next, total);
        }
        assert_eq!(Shard::new(1, 3).unwrap().trials(120), 40..80);
        assert!(matches!(
            Shard::new(0, 5).unwrap().nonempty_trials(3),
            Err(ShardError::Empty { .. })
        ));
    }

    #[test]
    fn shard_text_is_parsed_and_bad_text_refused() {
        assert_eq!(
            "2/4".parse::<ShardRequest>(),
            Ok(ShardRequest::Given(Shard { index: 2, count: 4 }))
        );
        assert_eq!("auto".parse(), Ok(ShardRequest::Auto(None)));
        assert_eq!("auto/8".parse(), Ok(ShardRequest::Auto(Some(8))));
        for bad in ["4/4", "1/0", "x/2", "2", "auto/0", "1/2/3", ""] {
            assert!(bad.parse::<ShardRequest>().is_err(), "{bad}");
        }
    }

    #[test]
    fn auto_reads_slurm_or_kubernetes_and_says_when_neither_is_set() {
        let auto = ShardRequest::Auto(None);
        let slurm = env(&[
            ("SLURM_ARRAY_TASK_ID", "2"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert_eq!(auto.resolve(slurm), Ok(Shard { index: 2, count: 4 }));
        let from_one = env(&[
            ("SLURM_ARRAY_TASK_ID", "4"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert_eq!(auto.resolve(from_one), Ok(Shard { index: 3, count: 4 }));
        let stepped = env(&[
            ("SLURM_ARRAY_TASK_ID", "6"),
            ("SLURM_ARRAY_TASK_MIN", "0"),
            ("SLURM_ARRAY_TASK_STEP", "2"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert_eq!(auto.resolve(stepped), Ok(Shard { index: 3, count: 4 }));
        let k8s = env(&[("JOB_COMPLETION_INDEX", "1")]);
        assert_eq!(
            ShardRequest::Auto(Some(3)).resolve(&k8s),
            Ok(Shard { index: 1, count: 3 })
        );
        assert_eq!(
            auto.resolve(&k8s),
            Err(ShardError::CountMissing { index: 1 })
        );
        let none = auto.resolve(env(&[])).unwrap_err();
        assert_eq!(none, ShardError::NoScheduler);
        assert!(none.to_string().contains("SLURM_ARRAY_TASK_ID"), "{none}");
        let wrong = env(&[
            ("SLURM_ARRAY_TASK_ID", "1"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert_eq!(
            ShardRequest::Auto(Some(3)).resolve(wrong),
            Err(ShardError::CountMismatch { given: 3, found: 4 })
        );
        let garbled = env(&[("SLURM_ARRAY_TASK_ID", "one")]);
        assert!(matches!(
            auto.resolve(garbled),
            Err(ShardError::Variable { .. })
        ));
    }
}
