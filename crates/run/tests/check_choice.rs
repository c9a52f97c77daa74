//! Contract: with a walking check, `RUN/best/` keeps the policy the check ranks highest, not
//! the one with the highest learning-curve value. Two candidates: the later one scores the
//! higher (sampled) return but falls from more starts; the kept policy is the earlier one.
//! Without a check the same rows keep the later one, so the test can tell the two rules
//! apart.

use esrl_agents::{
    Agent, AgentError, EpisodeReport, Learner, ReplayBuffer, Resumable, Trainer, TrainerState,
};
use esrl_run::check::{CheckConfig, CheckRecord, Trigger};
use esrl_run::checkpoint::{self, BestInfo, BEST, BEST_INFO};
use esrl_run::restart::RestartConfig;
use esrl_run::training::CHECKS_FILE;
use esrl_run::{build, AgentKind, EnvKind, Preset, TrainConfig, Training};
use esrl_sim::MakeEnv;
use std::collections::HashMap;

/// A learner whose rows are given: each row's curve value and the actor genome that scored
/// it, and the genome of its search distribution's mean, if any. Everything a checkpoint
/// needs comes from an inner trainer.
struct Scripted {
    inner: Trainer,
    rows: Vec<(f64, Vec<f32>)>,
    mean: Option<Vec<f32>>,
    done: usize,
}

impl Learner for Scripted {
    type Row = EpisodeReport;
    const UNIT: &'static str = "episode";

    fn run_row(&mut self, _envs: &MakeEnv) -> Result<EpisodeReport, AgentError> {
        let (curve, _) = &self.rows[self.done];
        self.done += 1;
        Ok(EpisodeReport {
            episode: self.done - 1,
            env_steps: self.done as u64 * 10,
            curve: *curve,
            ret: *curve,
            length: 10,
            terminated: false,
            q0: 0.0,
            critic_loss: None,
            actor_loss: None,
            alpha: None,
            updates: 0,
        })
    }

    fn rows(&self) -> usize {
        self.done
    }

    fn env_steps(&self) -> u64 {
        self.done as u64 * 10
    }

    fn agent(&self) -> &Agent {
        self.inner.agent()
    }

    fn scored_agent(&self) -> Result<Option<Agent>, AgentError> {
        let mut agent = self.inner.agent().clone();
        agent.set_genome(&self.rows[self.done - 1].1)?;
        Ok(Some(agent))
    }

    fn mean_agent(&self) -> Result<Option<Agent>, AgentError> {
        let Some(mean) = &self.mean else {
            return Ok(None);
        };
        let mut agent = self.inner.agent().clone();
        agent.set_genome(mean)?;
        Ok(Some(agent))
    }
}

impl Resumable for Scripted {
    type LoopState = ();

    fn buffer(&self) -> &ReplayBuffer {
        self.inner.buffer()
    }

    fn state(&self) -> TrainerState {
        self.inner.state()
    }

    fn tensors(&self) -> Vec<(String, Vec<f32>)> {
        self.inner.agent().state_tensors()
    }

    fn check(&self, _: &TrainerState, _: usize) -> Result<(), AgentError> {
        Ok(())
    }

    fn restore(
        &mut self,
        _: TrainerState,
        _: &HashMap<String, Vec<f32>>,
        _: ReplayBuffer,
    ) -> Result<(), AgentError> {
        Ok(())
    }
}

/// The walking preset on 3 s episodes with full-range targets (±1 reach the joint limits),
/// checked from 4 starts; `check` off gives the curve rule.
fn config(check: bool) -> TrainConfig {
    let mut cfg = TrainConfig::preset(AgentKind::EsSac, EnvKind::Walk, Preset::Walking);
    cfg.walk.episode_seconds = 3.0;
    cfg.walk.target.range = None;
    cfg.threads = 2;
    cfg.checkpoint_every = 1000;
    cfg.check = check.then(|| CheckConfig {
        starts: 4,
        every_steps: 1_000_000,
        ..CheckConfig::default()
    });
    cfg
}

/// Trains the two scripted rows into a fresh folder; returns `best.json` and the check log.
fn train(check: bool) -> (BestInfo, Vec<CheckRecord>) {
    train_with(config(check))
}

/// [`train`] with any configuration.
fn train_with(cfg: TrainConfig) -> (BestInfo, Vec<CheckRecord>) {
    train_rows(cfg, false)
}

/// [`train_with`], the policy that falls first when `falls_first` (it then scores the lower
/// curve value, so both rows still set a new best).
fn train_rows(cfg: TrainConfig, falls_first: bool) -> (BestInfo, Vec<CheckRecord>) {
    let (stands, falls) = genomes(&cfg);
    let rows = if falls_first {
        vec![(1.0, falls), (5.0, stands)]
    } else {
        vec![(1.0, stands), (5.0, falls)]
    };
    let (best, records, _) = train_scripted(cfg, rows, None);
    (best, records)
}

/// A genome that stands and one that falls: a zero actor holds the standing pose (action 0
/// is the standing target); an actor of all 0.05 drives every joint towards its upper limit
/// and falls.
fn genomes(cfg: &TrainConfig) -> (Vec<f32>, Vec<f32>) {
    let envs = build::envs(cfg.env, &cfg.walk).unwrap();
    let n = build::agent(cfg, &envs).unwrap().genome_len();
    (vec![0.0f32; n], vec![0.05f32; n])
}

/// Trains the scripted `rows` (with the search mean `mean`) into a fresh folder; returns
/// `best.json`, the check log and the genome `RUN/best/` holds.
fn train_scripted(
    cfg: TrainConfig,
    rows: Vec<(f64, Vec<f32>)>,
    mean: Option<Vec<f32>>,
) -> (BestInfo, Vec<CheckRecord>, Vec<f32>) {
    let run = run_scripted(cfg, rows, mean, None);
    (run.best, run.records, run.kept)
}

/// What a scripted run left.
struct ScriptedRun {
    best: BestInfo,
    records: Vec<CheckRecord>,
    /// `checks.jsonl` as written.
    log: String,
    /// The genome `RUN/best/` holds.
    kept: Vec<f32>,
    /// [`Training::best_distance`] at the end.
    distance: Option<f64>,
    /// Whether the run found a first walk.
    walked: bool,
}

/// [`train_scripted`], the learner's agent holding `start` before the first row when given
/// (the policy a run with `init` starts from).
fn run_scripted(
    cfg: TrainConfig,
    rows: Vec<(f64, Vec<f32>)>,
    mean: Option<Vec<f32>>,
    start: Option<&[f32]>,
) -> ScriptedRun {
    let envs = build::envs(cfg.env, &cfg.walk).unwrap();
    let mut agent = build::agent(&cfg, &envs).unwrap();
    if let Some(genome) = start {
        agent.set_genome(genome).unwrap();
    }
    let learner = Scripted {
        inner: Trainer::new(agent, cfg.seed),
        rows,
        mean,
        done: 0,
    };
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("run");
    let (mut t, _) = Training::open(&cfg, &root, learner, envs.make.clone(), false).unwrap();
    t.step().unwrap();
    t.step().unwrap();
    // The second row's check runs beside the next row or, as here, before the last
    // checkpoint.
    t.finish(true).unwrap();
    let best: BestInfo =
        serde_json::from_str(&std::fs::read_to_string(root.join(BEST).join(BEST_INFO)).unwrap())
            .unwrap();
    let log = std::fs::read_to_string(root.join(CHECKS_FILE)).unwrap_or_default();
    let records = log
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let mut kept = build::agent(&cfg, &envs).unwrap();
    checkpoint::load_agent(&root.join(BEST), &mut kept).unwrap();
    ScriptedRun {
        best,
        records,
        log,
        kept: kept.genome(),
        distance: t.best_distance(),
        walked: t.first_walk().is_some(),
    }
}

#[test]
fn the_check_keeps_the_policy_that_falls_less_over_the_higher_return() {
    let (best, checks) = train(true);
    assert_eq!(checks.len(), 2, "both rows set a new best curve value");
    let (first, second) = (&checks[0].result, &checks[1].result);
    assert!(
        second.falls > first.falls,
        "the scripted policies must differ in falls: {} vs {}",
        first.describe(),
        second.describe()
    );
    assert!(checks[0].kept && !checks[1].kept);
    assert_eq!(best.generation, 0, "best/ keeps the policy that falls less");
    assert_eq!(best.check.as_ref(), Some(first));
}

#[test]
fn without_a_check_the_higher_return_is_kept() {
    let (best, checks) = train(false);
    assert!(checks.is_empty());
    assert_eq!(best.generation, 1);
    assert_eq!(best.check, None);
}

/// The walking preset's short configuration with `check.stop_early` and `restart`.
fn stopping(restart: Option<RestartConfig>) -> TrainConfig {
    let mut cfg = config(true);
    if let Some(check) = &mut cfg.check {
        check.stop_early = true;
    }
    cfg.restart = restart;
    cfg
}

/// Each check's (starts, stopped, completed).
fn shapes(records: &[CheckRecord]) -> Vec<(usize, bool, bool)> {
    assert_eq!(records.len(), 2, "both rows set a new best curve value");
    records
        .iter()
        .map(|r| (r.result.starts, r.result.stopped, r.result.completed))
        .collect()
}

/// Contract: with `check.stop_early`, a check stops at the start that puts the bar out of
/// reach only once `[restart]` can no longer start the run over; until then every start runs,
/// since the rule reads the checks' mean distance.
#[test]
fn checks_stop_early_only_once_the_restart_rule_is_settled() {
    let checks = |restart| shapes(&train_with(stopping(restart)).1);
    // No rule: neither policy reaches the line. The first check, with nothing kept yet, runs
    // in full after all; the second (it falls at its first start) ranks below the kept
    // standing policy there and stops.
    assert_eq!(checks(None), [(4, false, true), (1, true, false)]);
    // A rule that may still fire (no check went 15 m): every start runs.
    let open = RestartConfig {
        at_steps: 1_000_000_000,
        ..RestartConfig::default()
    };
    assert_eq!(
        checks(Some(open.clone())),
        [(4, false, false), (4, false, false)]
    );
    // A rule that any check settles (0 m): the first check runs in full, the second stops.
    let settled = RestartConfig {
        min_distance: 0.0,
        ..open
    };
    assert_eq!(checks(Some(settled)), [(4, false, false), (1, true, false)]);
}

/// Contract: the kept policy is chosen on full records only. A check that stops with its
/// starts so far ranking it above the kept policy runs its remaining starts before it can
/// replace it.
#[test]
fn a_stopped_check_that_ranks_above_the_kept_policy_runs_in_full() {
    let (best, records) = train_rows(stopping(None), true);
    // The falling policy is checked first (in full: nothing is kept); standing still, which
    // does not fall at its first start, ranks above it there, so its check runs every start
    // and replaces it.
    assert_eq!(shapes(&records), [(4, false, true), (4, false, true)]);
    assert!(records[0].result.falls > records[1].result.falls);
    assert!(records[0].kept && records[1].kept);
    assert_eq!(best.generation, 1);
    assert_eq!(best.check.as_ref(), Some(&records[1].result));
}

/// The short walking configuration with `check.mean`.
fn with_mean() -> TrainConfig {
    let mut cfg = config(true);
    cfg.check.as_mut().unwrap().mean = true;
    cfg
}

/// Each check's (row, mean, kept).
fn roles(records: &[CheckRecord]) -> Vec<(usize, bool, bool)> {
    records.iter().map(|r| (r.row, r.mean, r.kept)).collect()
}

/// Contract (`check.mean`): each policy due a check is checked after the ES mean, with the
/// same starts, and both are ranked as candidates. Here the mean stands and the second row's
/// individual falls: the mean is kept over it; the first row's individual, which stands as
/// the mean does, only ties and does not replace the mean checked before it.
#[test]
fn the_es_mean_is_checked_first_and_kept_over_individuals_that_do_not_beat_it() {
    let cfg = with_mean();
    let (stands, falls) = genomes(&cfg);
    let rows = vec![(1.0, stands.clone()), (5.0, falls.clone())];
    let (best, records, kept) = train_scripted(cfg, rows.clone(), Some(stands.clone()));
    assert_eq!(
        roles(&records),
        [
            (0, true, true),
            (0, false, false),
            (1, true, false),
            (1, false, false)
        ],
        "(row, mean, kept) of each check"
    );
    assert_eq!(
        records[0].result, records[1].result,
        "the same policy from the same starts"
    );
    assert!(records[3].result.falls > records[2].result.falls);
    assert!(best.mean && best.generation == 0);
    assert_eq!(best.check.as_ref(), Some(&records[0].result));
    assert_eq!(kept, stands, "RUN/best/ holds the mean's genome");

    // A mean that falls is checked and ranked the same way, and loses to the individual.
    let (best, records, kept) = train_scripted(config(true), rows.clone(), Some(falls.clone()));
    assert_eq!(
        records.len(),
        2,
        "without check.mean the mean is not checked"
    );
    assert!(records.iter().all(|r| !r.mean) && !best.mean);
    assert_eq!(kept, stands);
    let cfg = with_mean();
    let (best, records, kept) = train_scripted(cfg, rows, Some(falls));
    assert_eq!(
        roles(&records),
        [
            (0, true, true),
            (0, false, true),
            (1, true, false),
            (1, false, false)
        ]
    );
    assert!(!best.mean && best.generation == 0);
    assert_eq!(kept, stands);
}

/// Contract (`init`): a run started from a trained policy checks that policy beside its
/// first row, as a candidate for `RUN/best/` only. Here it stands and every policy the run
/// trains falls: the start is kept (`best.json` says so), and its check neither times a
/// walk nor counts for the restart rule's distance. Without `init` nothing more is checked.
#[test]
fn a_run_started_from_a_policy_keeps_it_until_a_trained_one_ranks_above_it() {
    let mut cfg = config(true);
    cfg.init = Some("the-start".into());
    let (stands, falls) = genomes(&cfg);
    let rows = vec![(1.0, falls.clone()), (5.0, falls.clone())];
    let run = run_scripted(cfg.clone(), rows, None, Some(&stands));
    let (records, best) = (&run.records, &run.best);
    assert_eq!(records.len(), 3, "the start and both rows");
    assert_eq!(records[0].trigger, Trigger::Start);
    assert_eq!((records[0].row, records[0].env_steps), (0, 0));
    assert!(
        run.log
            .lines()
            .next()
            .unwrap()
            .contains("\"trigger\":\"start\""),
        "{}",
        run.log
    );
    assert!(records[1].result.falls > records[0].result.falls);
    assert_eq!(
        records.iter().map(|r| r.kept).collect::<Vec<_>>(),
        [true, false, false]
    );
    assert!(
        best.start && best.generation == 0 && best.env_steps == 0,
        "{best:?}"
    );
    assert_eq!(best.check.as_ref(), Some(&records[0].result));
    assert_eq!(run.kept, stands, "RUN/best/ holds the start");
    let trained = records[1..]
        .iter()
        .map(|r| r.result.mean_distance)
        .fold(f64::NEG_INFINITY, f64::max);
    // (checks.jsonl's numbers are read back from JSON: equal to the last digit or so.)
    let read = run.distance.expect("the trained checks' distance");
    assert!(
        (read - trained).abs() < 1e-12 && (read - records[0].result.mean_distance).abs() > 1e-3,
        "the restart rule reads the trained checks' {trained} m, not the start's: {read}"
    );
    assert!(!run.walked);

    // The same rows without `init`: two checks, the first row's policy kept.
    cfg.init = None;
    let (best, records) = train_with(cfg);
    assert_eq!(records.len(), 2);
    assert!(!best.start && records.iter().all(|r| r.trigger != Trigger::Start));
}
