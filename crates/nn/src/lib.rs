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
//! **time-major** order (row `t·B + b`), see [`Tensor`]. Products go through faer;
//! large ones are split by output rows or columns over the threads of the rayon pool they
//! run in, never along the summed dimension, so results do not depend on the thread count.
//!
//! # The pieces of an update
//!
//! A critic regression step, then an actor step through the frozen critic, then Polyak
//! averaging: the building blocks of SAC, TD3 and DDPG. The one update that training runs,
//! with burn-in, masks and every loss under its equation, is `esrl_agents::Agent::update`.
//!
//! ```
//! use esrl_nn::*;
//! use rand::SeedableRng;
//! use rand_chacha::ChaCha8Rng;
//!
//! let (obs_dim, act_dim, b, t) = (5, 2, 4, 3);
//! let acfg = ActorConfig { fc: vec![8], lstm_hidden: 6, ..ActorConfig::default() };
//! let ccfg = CriticConfig { obs_fc: vec![8], act_fc: vec![8], lstm_hidden: 7, ..CriticConfig::default() };
//! let mut actor = Actor::new(obs_dim, act_dim, &acfg, 1).unwrap();
//! let mut critic = Critic::new(obs_dim, act_dim, &ccfg, 2).unwrap();
//! let mut target = critic.clone();
//! let mut opt_pi = Adam::new(AdamConfig::default(), actor.params()).unwrap();
//! let mut opt_q = Adam::new(AdamConfig::default(), critic.params()).unwrap();
//! let mut rng = ChaCha8Rng::seed_from_u64(0);
//!
//! // B sequences of T steps, time-major (T·B, ·).
//! let x = |rows: usize, cols: usize, k: f32| {
//!     Tensor::from_vec(rows, cols, (0..rows * cols).map(|i| ((i as f32 + k) * 0.37).sin()).collect())
//! };
//! let (obs, act, y) = (x(t * b, obs_dim, 0.0), x(t * b, act_dim, 1.0), x(t * b, 1, 2.0));
//!
//! // Critic: mean squared error to the targets y, gradients into the critic.
//! let mut grads = {
//!     let mut g = Graph::new();
//!     let (o, a, yv) = (g.constant(obs.clone()), g.constant(act), g.constant(y));
//!     let q = critic.forward(&mut g, o, a, b, None).q;
//!     let loss = g.mse(q, yv);
//!     g.backward(loss)
//! };
//! opt_q.apply(critic.params_mut(), &mut grads).unwrap();
//!
//! // Actor: maximise Q(s, ã) with ã sampled from the policy; the frozen critic passes the
//! // gradient through its action input and computes none for its own weights.
//! let mut grads = {
//!     let mut g = Graph::new();
//!     g.freeze(critic.params());
//!     let o = g.constant(obs);
//!     let out = actor.forward(&mut g, o, b, None);
//!     let s = actor.sample(&mut g, &out, &mut rng);
//!     let q = critic.forward(&mut g, o, s.action, b, None).q;
//!     let mean_q = g.mean(q);
//!     let loss = g.neg(mean_q);
//!     g.backward(loss)
//! };
//! assert!(grads.of(critic.params()).is_none());
//! opt_pi.apply(actor.params_mut(), &mut grads).unwrap();
//!
//! // Polyak averaging of the target (eq. 7).
//! target.params_mut().polyak_update(critic.params(), 0.005).unwrap();
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
//! All products are faer's (AVX-512/AVX2 kernels chosen at runtime), each block on one
//! thread (products of ≥ 2²² multiply-adds are split into one block per pool thread); the
//! LSTM's input projection for all T steps is one product, BPTT runs inside one op, the
//! cell's nonlinearities are vectorised rational/polynomial approximations, and large
//! buffers are recycled through a per-thread pool so steady-state updates do not fault pages
//! in. [`bench::run`] measures the paper networks' forward and backward passes; `scripts/compare.sh` times PyTorch on the
//! same shapes in the same session.
//!
//! # Limitations
//!
//! - f32 only, 2-D tensors only; sequences are time-major matrices.
//! - Results are bit-identical run to run and independent of the thread count, but not
//!   across CPUs with different SIMD widths (faer picks different kernels).
//! - One LSTM layer per network and one bias vector per LSTM (PyTorch has two; load ours
//!   into PyTorch as `bias_ih = bias`, `bias_hh = 0`).
//! - Only the matrix products use more than one thread; the LSTM cell, the element-wise ops
//!   and Adam run on the calling thread.
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
pub mod subnormal;

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

/// Hands a large buffer that is no longer needed (a parameter gradient taken out of
/// [`Gradients`] once the optimiser has used it) back to this thread's pool, so the next
/// reverse pass reuses it instead of allocating and zeroing a new one.
pub fn recycle(buf: Vec<f32>) {
    pool::recycle(buf);
}
