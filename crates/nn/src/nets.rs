//! The actor and critic of the paper (Fig. 1a, 1b) and their feed-forward variants.

use crate::error::NnError;
use crate::graph::{Graph, Var};
use crate::layers::{Linear, Lstm, LstmState, Mlp};
use crate::ops::linear::Layout;
use crate::ops::Act;
use crate::params::Params;
use crate::tensor::Tensor;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

/// Anything that owns a [`Params`] set.
pub trait Module {
    /// The parameters.
    fn params(&self) -> &Params;
    /// The parameters, mutable (optimiser steps, ES perturbations, loading).
    fn params_mut(&mut self) -> &mut Params;
    /// Number of scalar parameters.
    fn num_params(&self) -> usize {
        self.params().len()
    }
}

/// Largest layer width or LSTM size accepted: far above any locomotion network (the paper's
/// widest layer is 256), low enough that one layer's weights cannot exhaust memory by a typo.
pub const MAX_WIDTH: usize = 16_384;

/// A layer that reads a feature-major stack's output and writes (N, out).
const FROM_FEATURE_MAJOR: Layout = Layout {
    x_t: true,
    y_t: false,
};

fn check_widths(field: &str, widths: &[usize]) -> Result<(), NnError> {
    for (k, &w) in widths.iter().enumerate() {
        check_dim(&format!("{field}[{k}]"), w)?;
    }
    Ok(())
}

fn check_dim(field: &str, v: usize) -> Result<(), NnError> {
    if v == 0 || v > MAX_WIDTH {
        return Err(NnError::Config {
            field: field.into(),
            value: v.to_string(),
            reason: format!("must be in 1..={MAX_WIDTH}"),
        });
    }
    Ok(())
}

/// Parameters of an MLP from `input` through `widths` (weights and biases).
fn mlp_params(input: usize, widths: &[usize]) -> (usize, usize) {
    widths
        .iter()
        .fold((0, input), |(n, d), &w| (n + (d + 1) * w, w))
}

/// Parameters of an LSTM layer: four gates, each with input and recurrent weights and one
/// bias vector.
fn lstm_params(input: usize, hidden: usize) -> usize {
    4 * hidden * (input + hidden + 1)
}

/// Sizes of the actor (paper Fig. 1a).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ActorConfig {
    /// FC+ReLU widths applied to the observation. Default `[256]`: one FC layer of 256, which
    /// with `lstm_hidden = 100` gives 155,276 parameters for the walking env (obs 43, act 6),
    /// +1.0% of the paper's 153.7k.
    pub fc: Vec<usize>,
    /// Whether an LSTM follows the FC layers. Default `true` (the paper's recurrent actor);
    /// `false` is the feed-forward variant.
    pub recurrent: bool,
    /// LSTM hidden units. Default 100 (chosen to match the paper's parameter count).
    pub lstm_hidden: usize,
    /// Added to the Softplus standard deviation so it never reaches 0. Default 1e-5 (as in
    /// `peers/torch_sac_step.py`).
    pub min_std: f32,
}

impl Default for ActorConfig {
    fn default() -> Self {
        Self {
            fc: vec![256],
            recurrent: true,
            lstm_hidden: 100,
            min_std: 1e-5,
        }
    }
}

impl ActorConfig {
    /// The paper's recurrent actor (the default).
    pub fn paper() -> Self {
        Self::default()
    }

    /// Feed-forward variant: FC 256×256 (ReLU) → heads, no LSTM (pendulum, MLP benchmark).
    pub fn feed_forward() -> Self {
        Self {
            fc: vec![256, 256],
            recurrent: false,
            ..Self::default()
        }
    }

    /// Parameter count of this actor for the given sizes, without building it (memory
    /// estimates before allocation).
    pub fn param_count(&self, obs_dim: usize, act_dim: usize) -> usize {
        let (mut n, mut d) = mlp_params(obs_dim, &self.fc);
        if self.recurrent {
            n += lstm_params(d, self.lstm_hidden);
            d = self.lstm_hidden;
        }
        n + 2 * (d + 1) * act_dim
    }

    /// Checks every field; errors name the field.
    pub fn validate(&self) -> Result<(), NnError> {
        check_widths("actor.fc", &self.fc)?;
        if self.recurrent {
            check_dim("actor.lstm_hidden", self.lstm_hidden)?;
        }
        if !(self.min_std.is_finite() && self.min_std >= 0.0) {
            return Err(NnError::Config {
                field: "actor.min_std".into(),
                value: self.min_std.to_string(),
                reason: "must be finite and ≥ 0".into(),
            });
        }
        Ok(())
    }
}

/// Sizes of the critic (paper Fig. 1b).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CriticConfig {
    /// FC+ReLU widths of the state path. Default `[128]`.
    pub obs_fc: Vec<usize>,
    /// FC+ReLU widths of the action path. Default `[128]`.
    pub act_fc: Vec<usize>,
    /// FC+ReLU widths after the two paths are concatenated. Default `[]` (the paper feeds
    /// the concatenation straight into the LSTM).
    pub joint_fc: Vec<usize>,
    /// Whether an LSTM follows. Default `true`; `false` is the feed-forward variant.
    pub recurrent: bool,
    /// LSTM hidden units. Default 112: with obs 43, act 6 the critic has 171,953 parameters,
    /// +1.4% of the paper's 169.6k.
    pub lstm_hidden: usize,
}

impl Default for CriticConfig {
    fn default() -> Self {
        Self {
            obs_fc: vec![128],
            act_fc: vec![128],
            joint_fc: vec![],
            recurrent: true,
            lstm_hidden: 112,
        }
    }
}

impl CriticConfig {
    /// The paper's recurrent critic (the default).
    pub fn paper() -> Self {
        Self::default()
    }

    /// Feed-forward variant: [obs | act] → FC 256×256 (ReLU) → Q, as the usual SAC MLP critic.
    pub fn feed_forward() -> Self {
        Self {
            obs_fc: vec![],
            act_fc: vec![],
            joint_fc: vec![256, 256],
            recurrent: false,
            lstm_hidden: 0,
        }
    }

    /// Parameter count of one critic for the given sizes, without building it.
    pub fn param_count(&self, obs_dim: usize, act_dim: usize) -> usize {
        let (n_obs, d_obs) = mlp_params(obs_dim, &self.obs_fc);
        let (n_act, d_act) = mlp_params(act_dim, &self.act_fc);
        let (n_joint, mut d) = mlp_params(d_obs + d_act, &self.joint_fc);
        let mut n = n_obs + n_act + n_joint;
        if self.recurrent {
            n += lstm_params(d, self.lstm_hidden);
            d = self.lstm_hidden;
        }
        n + d + 1
    }

    /// Checks every field; errors name the field.
    pub fn validate(&self) -> Result<(), NnError> {
        check_widths("critic.obs_fc", &self.obs_fc)?;
        check_widths("critic.act_fc", &self.act_fc)?;
        check_widths("critic.joint_fc", &self.joint_fc)?;
        if self.recurrent {
            check_dim("critic.lstm_hidden", self.lstm_hidden)?;
        }
        Ok(())
    }
}

/// What [`Actor::forward`] returns.
#[derive(Debug)]
pub struct ActorOutput {
    /// Pre-squash mean μ, (N, A).
    pub mean: Var,
    /// Standard deviation σ = softplus(·) + min_std, (N, A).
    pub std: Var,
    /// LSTM state after the last step (`None` for a feed-forward actor).
    pub state: Option<LstmState>,
}

/// A tanh-squashed Gaussian sample.
#[derive(Clone, Copy, Debug)]
pub struct PolicySample {
    /// Action in (−1, 1), (N, A).
    pub action: Var,
    /// log π(a | s), (N, 1).
    pub log_prob: Var,
}

/// The actor (paper Fig. 1a): FC+ReLU → LSTM → a mean head and a Softplus std head.
///
/// Tensor names: `fc.{k}.weight` (out, in), `fc.{k}.bias`, `lstm.weight_ih` (4H, I),
/// `lstm.weight_hh` (4H, H), `lstm.bias` (4H), `mean.weight` (A, H), `mean.bias` (A),
/// `std.weight` (A, H), `std.bias` (A).
#[derive(Clone, Debug)]
pub struct Actor {
    config: ActorConfig,
    obs_dim: usize,
    act_dim: usize,
    params: Params,
    trunk: Mlp,
    lstm: Option<Lstm>,
    /// Both heads as one layer of 2A outputs: rows [mean.weight; std.weight], bias
    /// [mean.bias; std.bias] (contiguous in the buffer, so one product serves both).
    heads: Linear,
}

impl Module for Actor {
    fn params(&self) -> &Params {
        &self.params
    }
    fn params_mut(&mut self) -> &mut Params {
        &mut self.params
    }
}

impl Actor {
    /// Builds an actor with weights drawn from `seed`.
    pub fn new(
        obs_dim: usize,
        act_dim: usize,
        config: &ActorConfig,
        seed: u64,
    ) -> Result<Self, NnError> {
        check_dim("actor.obs_dim", obs_dim)?;
        check_dim("actor.act_dim", act_dim)?;
        config.validate()?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut params = Params::new();
        let trunk = Mlp::new(&mut params, "fc", obs_dim, &config.fc, Act::Relu, &mut rng);
        let mut d = trunk.out_dim();
        let lstm = config.recurrent.then(|| {
            let l = Lstm::new(&mut params, "lstm", d, config.lstm_hidden, &mut rng);
            d = config.lstm_hidden;
            l
        });
        let heads = Linear::stacked(&mut params, ["mean", "std"], d, act_dim, &mut rng);
        Ok(Self {
            config: config.clone(),
            obs_dim,
            act_dim,
            params,
            trunk,
            lstm,
            heads,
        })
    }

    /// The configuration it was built with.
    pub fn config(&self) -> &ActorConfig {
        &self.config
    }

    /// Observation width.
    pub fn obs_dim(&self) -> usize {
        self.obs_dim
    }

    /// Action width A.
    pub fn act_dim(&self) -> usize {
        self.act_dim
    }

    /// LSTM hidden size, `None` for the feed-forward variant.
    pub fn lstm_hidden(&self) -> Option<usize> {
        self.lstm.map(|l| l.hidden())
    }

    /// The zero (h, c) for `batch` sequences (`None` for the feed-forward variant).
    pub fn zero_state(&self, batch: usize) -> Option<LstmState> {
        self.lstm.map(|l| LstmState::zeros(batch, l.hidden()))
    }

    /// Records the actor on `obs` (T·B, obs_dim) time-major, for B = `batch` sequences,
    /// starting from `state` (zeros when `None`; ignored by the feed-forward variant).
    pub fn forward<'a>(
        &'a self,
        g: &mut Graph<'a>,
        obs: Var,
        batch: usize,
        state: Option<&LstmState>,
    ) -> ActorOutput {
        let p = &self.params;
        let mut out_state = None;
        let feature_major = match self.lstm {
            None => self.trunk.forward_multi_feature_major(g, p, &[obs]),
            Some(_) => None,
        };
        let heads = match feature_major {
            // Feed-forward: the trunk's values stay feature-major up to the heads.
            Some(h) => self
                .heads
                .forward_in(g, p, &[h], Act::None, FROM_FEATURE_MAJOR),
            None => {
                let mut h = self.trunk.forward(g, p, obs);
                if let Some(l) = &self.lstm {
                    let o = l.forward(g, p, h, batch, state);
                    h = o.h;
                    out_state = Some(o.state);
                }
                self.heads.forward(g, p, h, Act::None)
            }
        };
        let mean = g.slice_cols(heads, 0, self.act_dim);
        let s = g.slice_cols(heads, self.act_dim, self.act_dim);
        let s = g.softplus(s);
        let std = g.add_scalar(s, self.config.min_std);
        ActorOutput {
            mean,
            std,
            state: out_state,
        }
    }

    /// Draws ε ~ N(0, I) from `rng` and records the squashed sample and its log-probability.
    pub fn sample<R: Rng + ?Sized>(
        &self,
        g: &mut Graph<'_>,
        out: &ActorOutput,
        rng: &mut R,
    ) -> PolicySample {
        let (n, a) = g.shape(out.mean);
        let eps: Vec<f32> = (0..n * a).map(|_| rng.sample(StandardNormal)).collect();
        self.sample_with_noise(g, out, Tensor::from_vec(n, a, eps))
    }

    /// Like [`Actor::sample`] with a given ε (N, A).
    pub fn sample_with_noise(
        &self,
        g: &mut Graph<'_>,
        out: &ActorOutput,
        eps: Tensor,
    ) -> PolicySample {
        let (action, log_prob) = g.gaussian_tanh(out.mean, out.std, eps);
        PolicySample { action, log_prob }
    }

    /// The deterministic action tanh(μ) (TD3/DDPG actors, evaluation).
    pub fn deterministic(&self, g: &mut Graph<'_>, out: &ActorOutput) -> Var {
        g.tanh(out.mean)
    }

    /// A fresh single-sequence inference state (zero (h, c) and scratch) for [`Actor::step`].
    pub fn step_state(&self) -> ActorStepState {
        let h = self.lstm_hidden().unwrap_or(0);
        let widest = self
            .config
            .fc
            .iter()
            .copied()
            .max()
            .unwrap_or(0)
            .max(self.obs_dim);
        ActorStepState {
            h: vec![0.0; h],
            c: vec![0.0; h],
            scratch: vec![0.0; 6 * h],
            buf_a: vec![0.0; widest],
            buf_b: vec![0.0; widest],
            heads: vec![0.0; 2 * self.act_dim],
        }
    }

    /// One control step for one sequence without a graph and without allocating: reads `obs`
    /// (obs_dim), advances `state`'s (h, c) and leaves μ and σ in `state.mean()`,
    /// `state.std()`.
    ///
    /// # Panics
    /// If `obs.len() != obs_dim` or `state` came from another architecture.
    pub fn step(&self, obs: &[f32], state: &mut ActorStepState) {
        assert_eq!(obs.len(), self.obs_dim, "Actor::step: observation length");
        let p = self.params.as_slice();
        let st = state;
        st.buf_a[..self.obs_dim].copy_from_slice(obs);
        let mut d = self.obs_dim;
        for l in self.trunk.layers() {
            l.apply_row(p, &st.buf_a[..d], &mut st.buf_b, Act::Relu);
            std::mem::swap(&mut st.buf_a, &mut st.buf_b);
            d = l.out_dim();
        }
        let feat: &[f32] = if let Some(l) = &self.lstm {
            l.step_row(p, &st.buf_a[..d], &mut st.h, &mut st.c, &mut st.scratch);
            &st.h
        } else {
            &st.buf_a[..d]
        };
        self.heads.apply_row(p, feat, &mut st.heads, Act::None);
        for s in st.heads[self.act_dim..].iter_mut() {
            *s = crate::kern::softplus(*s) + self.config.min_std;
        }
    }
}

/// Per-sequence state of [`Actor::step`]: (h, c) plus scratch, reused every step.
#[derive(Clone, Debug)]
pub struct ActorStepState {
    h: Vec<f32>,
    c: Vec<f32>,
    scratch: Vec<f32>,
    buf_a: Vec<f32>,
    buf_b: Vec<f32>,
    /// [μ | σ] of the last step.
    heads: Vec<f32>,
}

impl ActorStepState {
    /// Zeroes (h, c) for a new episode.
    pub fn reset(&mut self) {
        self.h.fill(0.0);
        self.c.fill(0.0);
    }

    /// μ of the last step (pre-squash).
    pub fn mean(&self) -> &[f32] {
        &self.heads[..self.heads.len() / 2]
    }

    /// σ of the last step.
    pub fn std(&self) -> &[f32] {
        &self.heads[self.heads.len() / 2..]
    }

    /// Hidden state h (empty for a feed-forward actor).
    pub fn h(&self) -> &[f32] {
        &self.h
    }

    /// Cell state c (empty for a feed-forward actor).
    pub fn c(&self) -> &[f32] {
        &self.c
    }

    /// Writes tanh(μ) into `action`.
    pub fn deterministic_action(&self, action: &mut [f32]) {
        for (a, &m) in action.iter_mut().zip(self.mean()) {
            *a = m.tanh();
        }
    }

    /// Writes tanh(μ + σε), ε ~ N(0, I) from `rng`, into `action`.
    pub fn sample_action<R: Rng + ?Sized>(&self, rng: &mut R, action: &mut [f32]) {
        for ((a, &m), &s) in action.iter_mut().zip(self.mean()).zip(self.std()) {
            let e: f32 = rng.sample(StandardNormal);
            *a = (m + s * e).tanh();
        }
    }
}

/// What [`Critic::forward`] returns.
#[derive(Debug)]
pub struct CriticOutput {
    /// Q(s, a), (N, 1).
    pub q: Var,
    /// LSTM state after the last step (`None` for a feed-forward critic).
    pub state: Option<LstmState>,
}

/// The critic (paper Fig. 1b): a state path and an action path of FC+ReLU layers,
/// concatenated, → LSTM → Q.
///
/// Tensor names: `obs_fc.{k}.weight`/`.bias`, `act_fc.{k}.*`, `fc.{k}.*` (joint layers),
/// `lstm.weight_ih` (4H, I), `lstm.weight_hh` (4H, H), `lstm.bias` (4H), `q.weight` (1, H),
/// `q.bias` (1).
#[derive(Clone, Debug)]
pub struct Critic {
    config: CriticConfig,
    obs_dim: usize,
    act_dim: usize,
    params: Params,
    obs_path: Mlp,
    act_path: Mlp,
    joint: Mlp,
    lstm: Option<Lstm>,
    q: Linear,
}

impl Module for Critic {
    fn params(&self) -> &Params {
        &self.params
    }
    fn params_mut(&mut self) -> &mut Params {
        &mut self.params
    }
}

impl Critic {
    /// Builds a critic with weights drawn from `seed`.
    pub fn new(
        obs_dim: usize,
        act_dim: usize,
        config: &CriticConfig,
        seed: u64,
    ) -> Result<Self, NnError> {
        check_dim("critic.obs_dim", obs_dim)?;
        check_dim("critic.act_dim", act_dim)?;
        config.validate()?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut params = Params::new();
        let obs_path = Mlp::new(
            &mut params,
            "obs_fc",
            obs_dim,
            &config.obs_fc,
            Act::Relu,
            &mut rng,
        );
        let act_path = Mlp::new(
            &mut params,
            "act_fc",
            act_dim,
            &config.act_fc,
            Act::Relu,
            &mut rng,
        );
        let joint = Mlp::new(
            &mut params,
            "fc",
            obs_path.out_dim() + act_path.out_dim(),
            &config.joint_fc,
            Act::Relu,
            &mut rng,
        );
        let mut d = joint.out_dim();
        let lstm = config.recurrent.then(|| {
            let l = Lstm::new(&mut params, "lstm", d, config.lstm_hidden, &mut rng);
            d = config.lstm_hidden;
            l
        });
        let q = Linear::new(&mut params, "q", d, 1, &mut rng);
        Ok(Self {
            config: config.clone(),
            obs_dim,
            act_dim,
            params,
            obs_path,
            act_path,
            joint,
            lstm,
            q,
        })
    }

    /// The configuration it was built with.
    pub fn config(&self) -> &CriticConfig {
        &self.config
    }

    /// Observation width.
    pub fn obs_dim(&self) -> usize {
        self.obs_dim
    }

    /// Action width.
    pub fn act_dim(&self) -> usize {
        self.act_dim
    }

    /// LSTM hidden size, `None` for the feed-forward variant.
    pub fn lstm_hidden(&self) -> Option<usize> {
        self.lstm.map(|l| l.hidden())
    }

    /// The zero (h, c) for `batch` sequences (`None` for the feed-forward variant).
    pub fn zero_state(&self, batch: usize) -> Option<LstmState> {
        self.lstm.map(|l| LstmState::zeros(batch, l.hidden()))
    }

    /// Records Q(s, a) for `obs` (T·B, obs_dim) and `act` (T·B, act_dim), time-major, for
    /// B = `batch` sequences from `state` (zeros when `None`).
    pub fn forward<'a>(
        &'a self,
        g: &mut Graph<'a>,
        obs: Var,
        act: Var,
        batch: usize,
        state: Option<&LstmState>,
    ) -> CriticOutput {
        let p = &self.params;
        let hs = self.obs_path.forward(g, p, obs);
        let ha = self.act_path.forward(g, p, act);
        // The two paths are joined without a copy: the next layer reads both blocks.
        let joined = [hs, ha];
        let mut xs: &[Var] = &joined;
        if self.lstm.is_none() {
            if let Some(h) = self.joint.forward_multi_feature_major(g, p, xs) {
                // Feed-forward: the joint stack's values stay feature-major up to Q.
                let q = self.q.forward_in(g, p, &[h], Act::None, FROM_FEATURE_MAJOR);
                return CriticOutput { q, state: None };
            }
        }
        let h;
        if !self.joint.layers().is_empty() {
            h = [self.joint.forward_multi(g, p, xs)];
            xs = &h;
        }
        let mut out_state = None;
        let lstm_out;
        if let Some(l) = &self.lstm {
            let o = l.forward_multi(g, p, xs, batch, state);
            lstm_out = [o.h];
            xs = &lstm_out;
            out_state = Some(o.state);
        }
        let q = self.q.forward_multi(g, p, xs, Act::None);
        CriticOutput {
            q,
            state: out_state,
        }
    }
}
