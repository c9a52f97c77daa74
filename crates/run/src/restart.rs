//! Starting a run over when it has not got going (`[restart]` in `config.toml`,
//! [`RestartConfig`]).
//!
//! Whether a seed of the walking recipe walks is visible early: in the seed study of the
//! default command (`results/torque`), every seed that reached the walking bar had a check
//! whose starts went 26 m or more on average by 0.75 M env steps, and the two that never
//! walked had gone at most 2.2 m (an in-place shuffle) and 8.3 m (a slow walk) by 1 M. A
//! run that has not got going by then is better started over than continued.
//!
//! **The rule.** When an attempt has taken [`RestartConfig::at_steps`] environment steps, has
//! not met the walking bar, and none of its walking checks carried the robot
//! [`RestartConfig::min_distance`] metres on average over the check's starts, it is abandoned
//! and the run starts over from seed `seed + 1000` (the next attempt from `seed + 2000`, and
//! so on), at most [`RestartConfig::max`] times. The rule is judged before every row from the
//! checks recorded so far, so a resumed run decides as an uninterrupted one does.
//!
//! **Attempt k is the run of seed `seed + 1000 k`**: the same learner, checks and files as
//! `esrl train … --seed <seed + 1000 k>` (without `[restart]`) until its own restart point,
//! so any attempt can be repeated alone. `RUN/config.toml` keeps the seed the run was given;
//! the summary gives the attempt's seed (`attempt_seed`) and counts the abandoned attempts'
//! steps and seconds in `steps_to_walk` and `time_to_walk_s` (what the walk cost), and in
//! `steps_to_any_walk` and `time_to_any_walk_s` when the run has them.
//!
//! **The budget.** Each attempt may take `max_env_steps`, unless
//! [`RestartConfig::whole_budget`] makes it the whole run's: then the abandoned attempts'
//! steps count against it and a restart does not lengthen the run.
//!
//! ```text
//! RUN/
//!   restarts.json          one record per abandoned attempt (Restart), written first
//!   restarts/seed-2/       that attempt's metrics, checks, summary and best/ (no
//!                          checkpoint, no replay)
//!   config.toml, metrics.jsonl, checks.jsonl, best/, checkpoint/, …   the attempt training now
//! ```
//!
//! A restart writes its record to `restarts.json` (not yet `settled`), moves the attempt's
//! files into `restarts/seed-S/`, deletes its checkpoint and replay, then marks the record
//! settled; only then does the next attempt start. A run killed in between finishes the move
//! when it is resumed ([`settle`]).

use crate::error::{Context, Result};
use crate::run_dir::{write_json_atomic, RunDir};
use crate::{bail, checkpoint};
use serde::{Deserialize, Serialize};
use std::fs;
use std::path::Path;

/// How a run starts over when it has not got going (`[restart]`; module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RestartConfig {
    /// The attempt's environment steps at which the rule is judged. Default 1,000,000.
    pub at_steps: u64,
    /// Metres a check's starts must have gone on average, in some check of the attempt, for
    /// it to go on. Default 15 (the walking bar's track is 50 m).
    pub min_distance: f64,
    /// Most restarts of one run. Default 2 (three attempts).
    pub max: usize,
    /// Whether `max_env_steps` is the whole run's budget: the abandoned attempts' env steps
    /// count against it, so a restart does not lengthen the run. Default false: each attempt
    /// may take `max_env_steps`.
    pub whole_budget: bool,
}

impl Default for RestartConfig {
    fn default() -> Self {
        Self {
            at_steps: 1_000_000,
            min_distance: 15.0,
            max: 2,
            whole_budget: false,
        }
    }
}

/// Most restarts a run may ask for.
pub const MAX_RESTARTS: usize = 9;

/// What each restart adds to the seed.
pub const SEED_STRIDE: u64 = 1000;

/// The file of a run's abandoned attempts.
pub const RESTARTS_FILE: &str = "restarts.json";

/// The folder that keeps the abandoned attempts' files.
pub const RESTARTS_DIR: &str = "restarts";

/// Entries of a run folder that belong to the run rather than to one attempt.
const RUN_ENTRIES: [&str; 6] = [
    RunDir::CONFIG,
    crate::init::INIT_FILE,
    crate::init::INIT_DIR,
    crate::training::LOCK_FILE,
    RESTARTS_FILE,
    RESTARTS_DIR,
];

impl RestartConfig {
    /// Checks every field, naming the first that cannot work.
    pub fn validate(&self) -> Result<()> {
        if self.at_steps == 0 {
            bail!("restart.at_steps = 0: must be ≥ 1");
        }
        if !(self.min_distance.is_finite() && self.min_distance >= 0.0) {
            bail!(
                "restart.min_distance = {}: must be a distance in metres, ≥ 0",
                self.min_distance
            );
        }
        if self.max == 0 || self.max > MAX_RESTARTS {
            bail!(
                "restart.max = {}: must be in 1..={MAX_RESTARTS} (leave [restart] out for none)",
                self.max
            );
        }
        Ok(())
    }

    /// Whether an attempt is abandoned now: it has taken `env_steps`, `restarts` attempts
    /// came before it, it has (`walked`) or has not met the walking bar, and its checks'
    /// longest mean distance is `best_distance` (`None` before its first check).
    pub fn due(
        &self,
        env_steps: u64,
        restarts: usize,
        walked: bool,
        best_distance: Option<f64>,
    ) -> bool {
        restarts < self.max
            && env_steps >= self.at_steps
            && !walked
            && best_distance.is_none_or(|d| d < self.min_distance)
    }
}

/// The seed of attempt `k` of a run of `seed` (attempt 0 is the run's own).
pub fn attempt_seed(seed: u64, k: usize) -> Result<u64> {
    (k as u64)
        .checked_mul(SEED_STRIDE)
        .and_then(|d| seed.checked_add(d))
        .with_context(|| format!("seed {seed}: its restart {k} would need a seed above 2^64"))
}

/// One abandoned attempt (`RUN/restarts.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Restart {
    /// The attempt's seed.
    pub seed: u64,
    /// Environment steps it took.
    pub env_steps: u64,
    /// Seconds it trained.
    pub wall_s: f64,
    /// Rows (generations or episodes) it ran.
    pub rows: usize,
    /// Its walking checks.
    pub checks: usize,
    /// The longest mean distance of its checks, metres (`None`: it was never checked).
    pub best_distance: Option<f64>,
    /// Where its files are, relative to the run folder.
    pub folder: String,
    /// Whether its files were moved there (the next attempt starts only after).
    pub settled: bool,
}

impl Restart {
    /// The folder of the attempt of `seed`, relative to the run folder.
    pub fn folder_of(seed: u64) -> String {
        format!("{RESTARTS_DIR}/seed-{seed}")
    }

    /// One line for a person: why the attempt was abandoned and what comes next.
    pub fn describe(&self, rule: &RestartConfig, next_seed: u64) -> String {
        let best = self.best_distance.map_or("no check yet".into(), |d| {
            format!("its checks went {d:.1} m at most")
        });
        format!(
            "seed {} has not got going after {} env steps ({best}, fewer than {} m): \
             starting over as seed {next_seed}; its files are in {}",
            self.seed, self.env_steps, rule.min_distance, self.folder
        )
    }
}

/// The abandoned attempts of the run in `root` (`RUN/restarts.json`), as written: the last
/// one not yet `settled` if a kill interrupted its restart (the training that takes the
/// folder's lock finishes it, [`settle`]). None for a run that never restarted.
pub fn read(root: &Path) -> Result<Vec<Restart>> {
    let p = root.join(RESTARTS_FILE);
    if !p.exists() {
        return Ok(Vec::new());
    }
    let text = fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
    serde_json::from_str(&text).with_context(|| format!("parsing {}", p.display()))
}

/// Abandons the attempt whose record is `restart`: records it in `restarts.json`, then moves
/// its files ([`settle`]). `restarts` holds the earlier records and gains this one.
pub fn abandon(root: &Path, restarts: &mut Vec<Restart>, restart: Restart) -> Result<()> {
    restarts.push(Restart {
        settled: false,
        ..restart
    });
    write_json_atomic(&root.join(RESTARTS_FILE), restarts)?;
    settle(root, restarts)
}

/// Finishes the restart of the last record if it is not settled: moves every entry of the
/// run folder that belongs to the attempt (all but `config.toml`, the lock and the restarts
/// themselves) into its folder, deleting the checkpoint and the replay, then marks it
/// settled. Safe to repeat after a kill at any point.
pub fn settle(root: &Path, restarts: &mut [Restart]) -> Result<()> {
    let Some(last) = restarts.last_mut() else {
        return Ok(());
    };
    if last.settled {
        return Ok(());
    }
    let dest = root.join(&last.folder);
    fs::create_dir_all(&dest).with_context(|| format!("creating {}", dest.display()))?;
    let throw = [
        "checkpoint",
        "checkpoint.old",
        "checkpoint.tmp",
        checkpoint::REPLAY,
    ];
    for entry in fs::read_dir(root).with_context(|| format!("reading {}", root.display()))? {
        let entry = entry?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if RUN_ENTRIES.contains(&name.as_str()) || name.starts_with('.') {
            continue;
        }
        let path = entry.path();
        if throw.contains(&name.as_str()) {
            fs::remove_dir_all(&path).with_context(|| format!("removing {}", path.display()))?;
        } else {
            let to = dest.join(&name);
            fs::rename(&path, &to)
                .with_context(|| format!("moving {} to {}", path.display(), to.display()))?;
        }
    }
    let config = root.join(RunDir::CONFIG);
    if config.exists() {
        fs::copy(&config, dest.join(RunDir::CONFIG))
            .with_context(|| format!("copying {}", config.display()))?;
    }
    last.settled = true;
    write_json_atomic(&root.join(RESTARTS_FILE), &restarts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_attempt_is_abandoned_only_past_its_steps_without_a_walk_or_a_long_check() {
        let rule = RestartConfig::default();
        let at = rule.at_steps;
        assert!(rule.due(at, 0, false, Some(14.9)));
        assert!(rule.due(at + 1, 1, false, None));
        assert!(!rule.due(at - 1, 0, false, Some(2.0)), "too early");
        assert!(!rule.due(at, 0, false, Some(15.0)), "it went far enough");
        assert!(!rule.due(at, 0, true, Some(2.0)), "it walked");
        assert!(!rule.due(at, 2, false, Some(2.0)), "no restarts left");
    }

    #[test]
    fn attempt_seeds_step_by_a_thousand_and_refuse_to_overflow() {
        assert_eq!(attempt_seed(2, 0).unwrap(), 2);
        assert_eq!(attempt_seed(2, 1).unwrap(), 1002);
        assert_eq!(attempt_seed(2, 2).unwrap(), 2002);
        assert!(attempt_seed(u64::MAX - 5, 1).is_err());
    }

    #[test]
    fn bad_settings_are_named() {
        for (rule, field) in [
            (
                RestartConfig {
                    at_steps: 0,
                    ..Default::default()
                },
                "at_steps",
            ),
            (
                RestartConfig {
                    min_distance: f64::NAN,
                    ..Default::default()
                },
                "min_distance",
            ),
            (
                RestartConfig {
                    max: 0,
                    ..Default::default()
                },
                "max",
            ),
        ] {
            let e = rule.validate().unwrap_err().to_string();
            assert!(e.contains(field), "{e}");
        }
    }

    #[test]
    fn settling_moves_the_attempt_and_keeps_the_run() {
        let tmp = tempfile::tempdir().unwrap();
        let root = tmp.path();
        for f in [
            "config.toml",
            "init.json",
            "metrics.jsonl",
            "checks.jsonl",
            ".lock",
        ] {
            fs::write(root.join(f), f).unwrap();
        }
        for d in ["best", "best-1M", "checkpoint", "replay", "init"] {
            fs::create_dir_all(root.join(d)).unwrap();
            fs::write(root.join(d).join("x"), d).unwrap();
        }
        let mut restarts = Vec::new();
        let record = Restart {
            seed: 2,
            env_steps: 1_000_100,
            wall_s: 60.0,
            rows: 900,
            checks: 40,
            best_distance: Some(2.2),
            folder: Restart::folder_of(2),
            settled: true,
        };
        abandon(root, &mut restarts, record).unwrap();
        let dest = root.join("restarts/seed-2");
        for f in [
            "config.toml",
            "metrics.jsonl",
            "checks.jsonl",
            "best/x",
            "best-1M/x",
        ] {
            assert!(dest.join(f).exists(), "{f} moved");
        }
        for gone in ["metrics.jsonl", "best", "best-1M", "checkpoint", "replay"] {
            assert!(!root.join(gone).exists(), "{gone} left the run folder");
        }
        // What the run started from belongs to every attempt.
        for kept in ["config.toml", "init.json", "init/x", ".lock"] {
            assert!(root.join(kept).exists(), "{kept} stays");
        }
        assert!(!dest.join("checkpoint").exists() && !dest.join("replay").exists());
        let read_back = read(root).unwrap();
        assert_eq!(read_back.len(), 1);
        assert!(read_back[0].settled && read_back[0].seed == 2);
    }

    #[test]
    fn a_restart_killed_before_its_move_is_finished_on_reading() {
        let tmp = tempfile::tempdir().unwrap();
        let root = tmp.path();
        fs::write(root.join("metrics.jsonl"), "old attempt").unwrap();
        let record = Restart {
            seed: 7,
            env_steps: 10,
            wall_s: 1.0,
            rows: 1,
            checks: 0,
            best_distance: None,
            folder: Restart::folder_of(7),
            settled: false,
        };
        // The record written, the kill before any file moved.
        write_json_atomic(&root.join(RESTARTS_FILE), &vec![record]).unwrap();
        let mut restarts = read(root).unwrap();
        assert!(!restarts[0].settled);
        settle(root, &mut restarts).unwrap();
        assert!(restarts[0].settled && read(root).unwrap()[0].settled);
        assert_eq!(
            fs::read_to_string(root.join("restarts/seed-7/metrics.jsonl")).unwrap(),
            "old attempt"
        );
        assert!(!root.join("metrics.jsonl").exists());
    }
}
