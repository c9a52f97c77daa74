//! Small reverse-mode autodiff over f32 matrices: MLP, LSTM with BPTT, Adam, safetensors.
//!
//! The networks of the paper (an LSTM actor with a tanh-squashed Gaussian head and twin LSTM
//! critics, Fig. 1) and exactly the machinery SAC, TD3 and DDPG need to train them:
//!
//! - a [`Graph`] (tape) of coarse ops — a whole [`Linear`], a whole [`Lstm`] sequence with
//!   BPTT inside, the Gaussian-tanh sample with its log-probability — plus elementwise ops,
//!   concatenation and reductions; every op's backward sits beside its forward;
//! - [`Params`]: each network's weights in one flat vector with named tensors, so the ES sees
//!   a flat genome, Polyak averaging and [`Adam`] are single loops, and checkpoints are
//!   safetensors files PyTorch and NumPy read ([`save_params`], [`load_params`]);
//! - [`Graph::freeze`] for gradients through a critic into its action input without the
//!   critic's weight gradients, and [`Graph::no_grad`] for targets and inference;
//! - [`Actor::step`] for rollouts: one observation at a time, no graph, no allocation.
//!
//! Matrices are row-major; a batch of B sequences × T steps is a `(T·B, D)` matrix in
//! **time-major** order (row `t·B + b`), see [`Tensor`]. Products go through faer,
//! single-threaded.
//!
//! # A SAC update
//!
//! ```
//! use esrl_nn::*;
//! use rand::SeedableRng;
//! use rand_chacha::ChaCha8Rng;
//!
//! let (obs_dim, act_dim, b, burn, t) = (5, 2, 4, 2, 3);
//! let acfg = ActorConfig { fc: vec![8], lstm_hidden: 6, ..ActorConfig::default() };
//! let ccfg = CriticConfig { obs_fc: vec![8], act_fc: vec![8], lstm_hidden: 7, ..CriticConfig::default() };
//! let mut actor = Actor::new(obs_dim, act_dim, &acfg, 1).unwrap();
//! let mut q1 = Critic::new(obs_dim, act_dim, &ccfg, 2).unwrap();
//! let mut q2 = Critic::new(obs_dim, act_dim, &ccfg, 3).unwrap();
//! let (mut q1_t, mut q2_t) = (q1.clone(), q2.clone());
//! let mut opt_pi = Adam::new(AdamConfig::default(), actor.params()).unwrap();
//! let mut opt_q1 = Adam::new(AdamConfig::default(), q1.params()).unwrap();
//! let mut opt_q2 = Adam::new(AdamConfig::default(), q2.params()).unwrap();
//! let mut rng = ChaCha8Rng::seed_from_u64(0);
//! let (gamma, alpha, tau) = (0.99f32, 0.2f32, 0.005f32);
//!
//! // A replay batch, time-major (T·B, ·): a burn-in prefix and the training part.
//! let x = |rows: usize, cols: usize, k: f32| {
//!     Tensor::from_vec(rows, cols, (0..rows * cols).map(|i| ((i as f32 + k) * 0.37).sin()).collect())
//! };
//! let (obs_burn, act_burn) = (x(burn * b, obs_dim, 0.0), x(burn * b, act_dim, 1.0));
//! let (obs, act, next_obs) = (x(t * b, obs_dim, 2.0), x(t * b, act_dim, 3.0), x(t * b, obs_dim, 4.0));
//! let (reward, not_done) = (x(t * b, 1, 5.0), Tensor::full(t * b, 1, 1.0));
//!
//! // Burn-in without gradients gives each network its initial (h, c).
//! let (sa, s1, s2, s1t, s2t) = {
//!     let mut g = Graph::no_grad();
//!     let (o, a) = (g.constant(obs_burn), g.constant(act_burn));
//!     (actor.forward(&mut g, o, b, None).state, q1.forward(&mut g, o, a, b, None).state,
//!      q2.forward(&mut g, o, a, b, None).state, q1_t.forward(&mut g, o, a, b, None).state,
//!      q2_t.forward(&mut g, o, a, b, None).state)
//! };
//!
//! // Target y = r + γ(1 − d)(min Q_t(s', a') − α log π(a'|s')), no gradient.
//! // (The next-observation sequence starts one step after `obs`; reusing the burn-in state
//! // is the usual approximation.)
//! let y = {
//!     let mut g = Graph::no_grad();
//!     let o2 = g.constant(next_obs);
//!     let out = actor.forward(&mut g, o2, b, sa.as_ref());
//!     let s = actor.sample(&mut g, &out, &mut rng);
//!     let qa = q1_t.forward(&mut g, o2, s.action, b, s1t.as_ref()).q;
//!     let qb = q2_t.forward(&mut g, o2, s.action, b, s2t.as_ref()).q;
//!     let qmin = g.minimum(qa, qb);
//!     let lp = g.scale(s.log_prob, alpha);
//!     let soft = g.sub(qmin, lp);
//!     let (r, nd) = (g.constant(reward), g.constant(not_done));
//!     let disc = g.mul(soft, nd);
//!     let disc = g.scale(disc, gamma);
//!     let y = g.add(r, disc);
//!     g.take_value(y)
//! };
//!
//! // Critic loss: MSE over B·T, gradients into both critics.
//! let mut grads = {
//!     let mut g = Graph::new();
//!     let (o, a, yv) = (g.constant(obs.clone()), g.constant(act), g.constant(y));
//!     let qa = q1.forward(&mut g, o, a, b, s1.as_ref()).q;
//!     let qb = q2.forward(&mut g, o, a, b, s2.as_ref()).q;
//!     let la = g.mse(qa, yv);
//!     let lb = g.mse(qb, yv);
//!     let loss = g.add(la, lb);
//!     g.backward(loss)
//! };
//! opt_q1.apply(q1.params_mut(), &mut grads).unwrap();
//! opt_q2.apply(q2.params_mut(), &mut grads).unwrap();
//!
//! // Actor loss mean(α log π − min(Q1, Q2)(s, ã)): the critics are frozen, so the gradient
//! // flows through their action input into the actor only.
//! let (mut grads, log_prob) = {
//!     let mut g = Graph::new();
//!     g.freeze(q1.params());
//!     g.freeze(q2.params());
//!     let o = g.constant(obs);
//!     let out = actor.forward(&mut g, o, b, sa.as_ref());
//!     let s = actor.sample(&mut g, &out, &mut rng);
//!     let qa = q1.forward(&mut g, o, s.action, b, s1.as_ref()).q;
//!     let qb = q2.forward(&mut g, o, s.action, b, s2.as_ref()).q;
//!     let qmin = g.minimum(qa, qb);
//!     let lp = g.scale(s.log_prob, alpha);
//!     let d = g.sub(lp, qmin);
//!     let loss = g.mean(d);
//!     let lp_values = g.value(s.log_prob).clone();
//!     (g.backward(loss), lp_values)
//! };
//! assert!(grads.of(q1.params()).is_none()); // frozen: no critic gradient computed
//! opt_pi.apply(actor.params_mut(), &mut grads).unwrap();
//!
//! // Entropy coefficient: L(log α) = −mean(log α · (log π + H̄)), so dL/dlog α = −mean(log π + H̄).
//! let target_entropy = -(act_dim as f32);
//! let d_log_alpha = -(log_prob.mean() + target_entropy);
//! assert!(d_log_alpha.is_finite());
//!
//! // Polyak averaging of the targets (eq. 7).
//! q1_t.params_mut().polyak_update(q1.params(), tau).unwrap();
//! q2_t.params_mut().polyak_update(q2.params(), tau).unwrap();
//! ```
//!
//! # Checkpoint tensors
//!
//! [`save_params`] writes F32 little-endian tensors with PyTorch shapes under stable names
//! (optionally behind a per-network prefix such as `actor.`). For the walking env (obs 43,
//! act 6) and the default configs:
//!
//! | actor | shape | critic | shape |
//! |---|---|---|---|
//! | `fc.0.weight` | (256, 43) | `obs_fc.0.weight` | (128, 43) |
//! | `fc.0.bias` | (256) | `obs_fc.0.bias` | (128) |
//! | `lstm.weight_ih` | (400, 256) | `act_fc.0.weight` | (128, 6) |
//! | `lstm.weight_hh` | (400, 100) | `act_fc.0.bias` | (128) |
//! | `lstm.bias` | (400) | `lstm.weight_ih` | (448, 256) |
//! | `mean.weight` | (6, 100) | `lstm.weight_hh` | (448, 112) |
//! | `mean.bias` | (6) | `lstm.bias` | (448) |
//! | `std.weight` | (6, 100) | `q.weight` | (1, 112) |
//! | `std.bias` | (6) | `q.bias` | (1) |
//!
//! LSTM gate blocks are PyTorch's [i; f; g; o]; load into `nn.LSTM` with
//! `weight_ih_l0 = lstm.weight_ih`, `weight_hh_l0 = lstm.weight_hh`, `bias_ih_l0 = lstm.bias`,
//! `bias_hh_l0 = 0` (`scripts/torch_parity.py` does exactly this and agrees to ~1e-7). The
//! flat vector ([`Params::as_slice`]) concatenates the tensors in [`Params::specs`] order.
//! Feed-forward variants name their layers `fc.{k}` (actor) and `fc.{k}` after the
//! concatenated input (critic).
//!
//! # Speed
//!
//! All products are faer's (AVX-512/AVX2 kernels chosen at runtime), single-threaded; the
//! LSTM's input projection for all T steps is one product, BPTT runs inside one op, the
//! cell's nonlinearities are vectorised rational/polynomial approximations, and large
//! buffers are recycled through a per-thread pool so steady-state updates do not fault pages
//! in. [`bench::run`] measures the paper networks; `scripts/compare.sh` times PyTorch on the
//! same shapes in the same session.
//!
//! # Limitations
//!
//! - f32 only, 2-D tensors only; sequences are time-major matrices.
//! - Results are bit-identical run to run and independent of the thread count, but not
//!   across CPUs with different SIMD widths (faer picks different kernels).
//! - One LSTM layer per network and one bias vector per LSTM (PyTorch has two; load ours
//!   into PyTorch as `bias_ih = bias`, `bias_hh = 0`).
//! - Single-threaded by design: parallelism belongs to the rollouts and the population.
//! - Shape errors between ops are programming errors and panic with the shapes; file, config
//!   and flat-vector errors are [`NnError`]s.

mod error;
mod gemm;
mod graph;
mod io;
mod kern;
mod layers;
mod nets;
mod ops;
mod optim;
mod params;
mod pool;
mod tensor;

pub mod bench;

pub use error::NnError;
pub use graph::{Gradients, Graph, Var};
pub use io::{load_params, load_tensors, save_params, save_tensors, NamedTensor};
pub use layers::{Linear, Lstm, LstmOutput, LstmState, Mlp};
pub use nets::{
    Actor, ActorConfig, ActorOutput, ActorStepState, Critic, CriticConfig, CriticOutput, Module,
    PolicySample, MAX_WIDTH,
};
pub use ops::Act;
pub use optim::{clip_grad_norm, Adam, AdamConfig, AdamState};
pub use params::{ParamSpec, Params};
pub use tensor::Tensor;
