//! Building what a configuration describes, in one place: its environments (the URDF parsed
//! once and shared), its agent, and its learner.

use crate::config::{EnvKind, TrainConfig};
use crate::error::{Context, Error, Result};
use esrl_agents::{Agent, Trainer};
use esrl_es::{Evaluator, Hybrid, HybridConfig, LocalEvaluator, Worker};
use esrl_sim::{Env, MakeEnv, Pendulum, RobotModel, WalkConfig, WalkEnv};
use std::sync::Arc;

/// The environments of a configuration: a factory every thread may call, the sizes the
/// networks need, and the robot model of walking runs.
#[derive(Clone)]
pub struct Envs {
    /// Makes a fresh environment per call.
    pub make: Arc<MakeEnv>,
    /// Observation width.
    pub obs_dim: usize,
    /// Action width.
    pub act_dim: usize,
    /// Steps after which an episode is truncated.
    pub max_episode_steps: usize,
    /// The parsed robot (walking runs).
    pub model: Option<Arc<RobotModel>>,
}

/// Loads the robot a walking config names: its URDF, or the embedded humanoid.
pub fn load_model(walk: &WalkConfig) -> Result<Arc<RobotModel>> {
    match &walk.urdf {
        Some(path) => match RobotModel::from_urdf_path(path) {
            Ok(model) => Ok(Arc::new(model)),
            // The read error names the file itself; the others need it said.
            Err(e @ esrl_sim::UrdfError::Io { .. }) => Err(e.into()),
            Err(e) => Err(e).with_context(|| format!("in URDF {}", path.display())),
        },
        None => RobotModel::humanoid_shared().context("loading the embedded humanoid"),
    }
}

/// The environments of `env` with the walking settings `walk`. Builds (and so validates)
/// one environment up front, so the factory itself cannot fail later.
pub fn envs(env: EnvKind, walk: &WalkConfig) -> Result<Envs> {
    match env {
        EnvKind::Pendulum => {
            let probe = Pendulum::new();
            Ok(Envs {
                make: Arc::new(|| Box::new(Pendulum::new()) as Box<dyn Env>),
                obs_dim: probe.obs_dim(),
                act_dim: probe.act_dim(),
                max_episode_steps: probe.max_episode_steps(),
                model: None,
            })
        }
        EnvKind::Walk => {
            let model = load_model(walk)?;
            let probe = WalkEnv::from_model(model.clone(), walk.clone()).with_context(|| {
                match &walk.urdf {
                    Some(p) => format!("building the walking environment from {}", p.display()),
                    None => "building the walking environment".into(),
                }
            })?;
            let (shared, walk) = (model.clone(), walk.clone());
            Ok(Envs {
                make: Arc::new(move || {
                    Box::new(
                        WalkEnv::from_model(shared.clone(), walk.clone())
                            .expect("the same model and config built an environment before"),
                    ) as Box<dyn Env>
                }),
                obs_dim: probe.obs_dim(),
                act_dim: probe.act_dim(),
                max_episode_steps: probe.max_episode_steps(),
                model: Some(model),
            })
        }
    }
}

/// A fresh agent of `cfg` for environments of these sizes, weights drawn from its seed.
pub fn agent(cfg: &TrainConfig, envs: &Envs) -> Result<Agent> {
    Agent::new(
        cfg.agent.algo(),
        envs.obs_dim,
        envs.act_dim,
        &cfg.network,
        &cfg.rl,
        cfg.seed,
    )
    .with_context(|| format!("building the {} agent", cfg.agent.name()))
}

/// The learner of a configuration: a plain trainer or the hybrid loop.
#[derive(Debug, Clone)]
pub enum AnyLearner {
    /// SAC / TD3 / DDPG.
    Plain(Box<Trainer>),
    /// ES-SAC / ES-TD3 / ES-DDPG.
    Hybrid(Box<Hybrid>),
}

/// The thread pool a run computes on, `threads` threads (one per core when 0): the hybrid
/// loop's rollouts and every learner's updates (their large products) share it. Results do
/// not depend on its size. More than 4 threads per core is refused.
pub fn pool(threads: usize) -> Result<rayon::ThreadPool> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    if threads > 4 * cores {
        return Err(Error::Msg(format!(
            "--threads {threads}: this machine has {cores} core(s), and more than 4 threads a \
             core only slows a run down (results do not depend on the thread count; 0 uses \
             every core)"
        )));
    }
    let threads = if threads == 0 { cores } else { threads };
    esrl_nn::subnormal::thread_pool(threads)
        .map_err(Error::other)
        .context("starting the thread pool")
}

/// A fresh learner of `cfg`. It computes on the rayon pool it is stepped in ([`pool`]; the
/// training session installs one of `cfg.threads`): the hybrid loop evaluates its populations
/// there.
pub fn learner(cfg: &TrainConfig, envs: &Envs) -> Result<AnyLearner> {
    learner_with(cfg, envs, local_evaluator(envs))
}

/// The evaluator that rolls populations out in this process, on the calling thread pool.
pub fn local_evaluator(envs: &Envs) -> Arc<dyn Evaluator> {
    Arc::new(LocalEvaluator::on_calling_pool(envs.make.clone()))
}

/// A fresh learner of `cfg` whose populations `evaluator` rolls out (a [`WireEvaluator`]
/// for workers in other processes); plain learners have none and ignore it. With
/// `cfg.init` its agent starts from those weights ([`crate::init`]), and the ES distribution
/// is centred on their actor.
///
/// [`WireEvaluator`]: esrl_es::WireEvaluator
pub fn learner_with(
    cfg: &TrainConfig,
    envs: &Envs,
    evaluator: Arc<dyn Evaluator>,
) -> Result<AnyLearner> {
    let mut agent = agent(cfg, envs)?;
    crate::init::load(cfg, &mut agent)?;
    let mirror = if cfg.rl.mirror {
        let env = WalkEnv::from_model(
            envs.model.clone().ok_or_else(|| {
                Error::Msg("rl.mirror needs the walking task (it has no mirror here)".into())
            })?,
            cfg.walk.clone(),
        )?;
        Some(
            env.mirror()
                .context("rl.mirror: the robot's left↔right mirror")?,
        )
    } else {
        None
    };
    Ok(if cfg.agent.is_hybrid() {
        let mut hybrid = Hybrid::new(agent, hybrid_config(cfg), cfg.seed, evaluator);
        hybrid.trainer_mut().set_mirror(mirror);
        AnyLearner::Hybrid(Box::new(hybrid))
    } else {
        let mut trainer = Trainer::new(agent, cfg.seed);
        trainer.set_mirror(mirror);
        AnyLearner::Plain(Box::new(trainer))
    })
}

/// The hybrid loop's settings of a run: its ES, inner cycles and update ratio.
pub fn hybrid_config(cfg: &TrainConfig) -> HybridConfig {
    HybridConfig {
        updates_per_step: cfg.updates_per_step,
        ..HybridConfig::new(cfg.es.clone(), cfg.inner_cycles)
    }
}

/// The worker side of a run's remote evaluation: rolls out genomes of the run configured by
/// `cfg` ([`Worker::rollout`]) with the policy its agent would hand out.
pub fn worker(cfg: &TrainConfig) -> Result<Worker> {
    let envs = envs(cfg.env, &cfg.walk)?;
    let policy = agent(cfg, &envs)?.policy();
    Ok(Worker::new(envs.make, policy))
}
