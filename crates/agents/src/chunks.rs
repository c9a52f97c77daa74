//! The deterministic parallel execution of an update, kept apart from its maths
//! (`sac.rs`, `td3.rs`): the batch is cut into `rl.batch_chunks` fixed
//! [`Part`]s that the losses run on side by side, random numbers are drawn for the whole
//! batch in row order and split like it, gradients are summed in part order, and the actor
//! loss's graph is cut at the action so the critics run side by side ([`through_critics`]).
//! None of it changes a number: one part gives exactly the numbers of one graph over the
//! batch, and the part bounds depend on the batch size and the chunk count only, never on
//! the thread count.

use esrl_nn::{Actor, Critic, Graph, LstmState, Module, NnError, Tensor, Var};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use rayon::prelude::*;

/// The trained part of a batch (its last `seq_len` steps) as tensors, time-major
/// `(len·B, ·)`, with the loss normaliser 1/M.
pub(crate) struct Trained {
    pub(crate) batch: usize,
    pub(crate) obs: Tensor,
    pub(crate) action: Tensor,
    pub(crate) reward: Tensor,
    pub(crate) next_obs: Tensor,
    /// 1 − terminated.
    pub(crate) not_done: Tensor,
    pub(crate) mask: Tensor,
    /// 1/M, M the number of masked (real) steps.
    pub(crate) norm: f32,
    /// α at the start of the update (0 without the entropy term).
    pub(crate) alpha: f32,
    /// The buffer's reward range when the batch was drawn.
    pub(crate) reward_range: (f32, f32),
}

/// Recurrent states after burn-in (`None` entries for feed-forward networks).
pub(crate) struct BurnIn {
    pub(crate) actor: Option<LstmState>,
    /// The actor that picks the target action (the target actor of TD3/DDPG), at s′.
    pub(crate) actor_next: Option<LstmState>,
    pub(crate) critics: Vec<Option<LstmState>>,
    pub(crate) critic_targets: Vec<Option<LstmState>>,
}

/// One share of a batch, batch entries `[b0, b1)` of the trained part: its tensors, its TD
/// targets and the networks' states after burn-in. The loss normaliser stays the whole
/// batch's 1/M, so the parts' losses and gradients sum to the whole batch's.
pub(crate) struct Part {
    /// The share's tensors, time-major.
    pub(crate) data: Trained,
    /// The TD targets y (eq. 3; empty until computed).
    pub(crate) y: Tensor,
    /// The actor's state at s.
    pub(crate) actor: Option<LstmState>,
    /// Each critic's state at (s, a).
    pub(crate) critics: Vec<Option<LstmState>>,
    /// The state of the actor that picks a′ at s′.
    pub(crate) actor_next: Option<LstmState>,
    /// Each target critic's state at (s′, a′).
    pub(crate) critic_targets: Vec<Option<LstmState>>,
}

/// `count` parts of `data` (one part: the whole batch, moved, not copied).
pub(crate) fn split(data: Trained, st: BurnIn, count: usize) -> Vec<Part> {
    let b = data.batch;
    if count <= 1 || b <= 1 {
        return vec![Part {
            data,
            y: Tensor::zeros(0, 0),
            actor: st.actor,
            critics: st.critics,
            actor_next: st.actor_next,
            critic_targets: st.critic_targets,
        }];
    }
    let count = count.min(b);
    (0..count)
        .map(|c| {
            let (b0, b1) = (c * b / count, (c + 1) * b / count);
            let rows = |t: &Tensor| batch_rows(t, b, b0, b1);
            let state = |s: &Option<LstmState>| {
                s.as_ref().map(|s| LstmState {
                    h: s.h.rows_range(b0, b1 - b0),
                    c: s.c.rows_range(b0, b1 - b0),
                })
            };
            Part {
                data: Trained {
                    batch: b1 - b0,
                    obs: rows(&data.obs),
                    action: rows(&data.action),
                    reward: rows(&data.reward),
                    next_obs: rows(&data.next_obs),
                    not_done: rows(&data.not_done),
                    mask: rows(&data.mask),
                    ..data
                },
                y: Tensor::zeros(0, 0),
                actor: state(&st.actor),
                critics: st.critics.iter().map(state).collect(),
                actor_next: state(&st.actor_next),
                critic_targets: st.critic_targets.iter().map(state).collect(),
            }
        })
        .collect()
}

/// The rows of batch entries `[b0, b1)` of a time-major `(len·B, cols)` tensor, time-major
/// `(len·(b1 − b0), cols)`.
fn batch_rows(t: &Tensor, batch: usize, b0: usize, b1: usize) -> Tensor {
    let cols = t.cols();
    let len = t.rows() / batch;
    let mut out = Vec::with_capacity(len * (b1 - b0) * cols);
    for step in 0..len {
        out.extend_from_slice(&t.data()[(step * batch + b0) * cols..(step * batch + b1) * cols]);
    }
    Tensor::from_vec(len * (b1 - b0), cols, out)
}

/// One standard normal per action dimension for every row of the batch, drawn from `rng` in
/// row order (the order one pass over the whole batch draws them) and split like the batch
/// into the parts' shares.
pub(crate) fn normal_noise(rng: &mut ChaCha8Rng, parts: &[Part], act_dim: usize) -> Vec<Tensor> {
    let b: usize = parts.iter().map(|p| p.data.batch).sum();
    let rows: usize = parts.iter().map(|p| p.data.obs.rows()).sum();
    let all: Vec<f32> = (0..rows * act_dim)
        .map(|_| rng.sample(StandardNormal))
        .collect();
    let all = Tensor::from_vec(rows, act_dim, all);
    if parts.len() == 1 {
        return vec![all];
    }
    let mut b0 = 0;
    parts
        .iter()
        .map(|p| {
            let b1 = b0 + p.data.batch;
            let share = batch_rows(&all, b, b0, b1);
            b0 = b1;
            share
        })
        .collect()
}

/// `f` on every part with its share of `each` (noise, a pass, …), side by side on the rayon
/// pool, results in part order.
pub(crate) fn each<T: Send, U: Send>(
    parts: &[Part],
    each: Vec<T>,
    f: impl Fn(&Part, T) -> U + Sync + Send,
) -> Vec<U> {
    parts.par_iter().zip(each).map(|(p, x)| f(p, x)).collect()
}

/// `f` on each part, side by side on the rayon pool; the results in part order.
pub(crate) fn each_part<U: Send>(parts: &[Part], f: impl Fn(&Part) -> U + Sync + Send) -> Vec<U> {
    parts.par_iter().map(f).collect()
}

/// Adds the parts' gradients (part order) into the first: the whole batch's gradient.
pub(crate) fn sum_in_order(mut parts: impl Iterator<Item = Vec<f32>>) -> Vec<f32> {
    let mut total = parts.next().expect("at least one part");
    for g in parts {
        for (t, x) in total.iter_mut().zip(&g) {
            *t += x;
        }
        esrl_nn::recycle(g);
    }
    total
}

/// The first half of a part's actor loss, which reads the actor only: its graph at s, the
/// action ã it gives and (SAC) log π(ã|s).
pub(crate) struct ActorPass<'a> {
    pub(crate) graph: Graph<'a>,
    pub(crate) act: Var,
    pub(crate) log_prob: Option<Var>,
}

/// A part's share of the actor loss, as [`through_critics`] returns it: the actor's
/// gradient, the loss and (SAC) log π of the samples.
pub(crate) type ActorPart = (Result<Vec<f32>, NnError>, f32, Option<Tensor>);

/// The actor's graph at a part's observations s, and its output there.
pub(crate) fn actor_graph<'a>(actor: &'a Actor, p: &Part) -> (Graph<'a>, esrl_nn::ActorOutput) {
    let mut graph = Graph::new();
    let ov = graph.constant(p.data.obs.clone());
    let out = actor.forward(&mut graph, ov, p.data.batch.max(1), p.actor.as_ref());
    (graph, out)
}

/// The second half of a part's actor loss from its [`ActorPass`]: the loss
/// 1/M Σ m·`per_step`(min_k Q_k(s, ã), log π) over the given `critics`, its value, the
/// actor's gradient and (SAC) log π.
///
/// The graph is cut at the action so the critics run side by side on the rayon pool: the
/// actor's graph gave ã (and log π); each critic's own graph gives Qₖ(s, ã) with ã as a
/// leaf; a small graph gives the loss, its value and its gradients with respect to min Qₖ
/// and log π; the minimum's derivative goes to the critic it chose (ties to the first, as
/// [`Graph::minimum`]); each critic's graph turns it into ∂L/∂ã; their sum, last critic
/// first as one graph's reverse pass would add them, and ∂L/∂log π seed the actor's reverse
/// pass. The same numbers as one graph of the whole loss.
pub(crate) fn through_critics(
    critics: &[Critic],
    actor: &Actor,
    part: &Part,
    pass: ActorPass<'_>,
    per_step: impl Fn(&mut Graph<'_>, Var, Option<Var>) -> Var,
) -> ActorPart {
    let p = &part.data;
    let batch = p.batch.max(1);
    let ActorPass {
        graph: mut ga,
        act,
        log_prob,
    } = pass;
    let action = ga.value(act).clone();

    // Each critic on its own graph: Qₖ(s, ã) with ã a leaf.
    let mut critic_graphs: Vec<_> = critics
        .par_iter()
        .zip(&part.critics)
        .map(|(c, state)| {
            let mut g = Graph::new();
            g.freeze(c.params());
            let o = g.constant(p.obs.clone());
            let a = g.leaf(action.clone());
            let q = c.forward(&mut g, o, a, batch, state.as_ref()).q;
            (g, a, q)
        })
        .collect();

    // min Qₖ, and which critic each element's minimum came from.
    let mut qmin = critic_graphs[0].0.value(critic_graphs[0].2).clone();
    let mut chosen = vec![0usize; qmin.len()];
    for (k, (g, _, q)) in critic_graphs.iter().enumerate().skip(1) {
        for ((m, c), &x) in qmin
            .data_mut()
            .iter_mut()
            .zip(&mut chosen)
            .zip(g.value(*q).data())
        {
            // `Graph::minimum`'s rule: the earlier operand unless it is not ≤ the
            // later one (NaN included).
            if (*m)
                .partial_cmp(&x)
                .is_none_or(|o| o == std::cmp::Ordering::Greater)
            {
                *c = k;
            }
            *m = m.min(x);
        }
    }

    // The loss from min Q and log π.
    let mut gl = Graph::new();
    let qv = gl.leaf(qmin);
    let mv = gl.constant(p.mask.clone());
    let lpv = log_prob.map(|lp| gl.leaf(ga.value(lp).clone()));
    let step = per_step(&mut gl, qv, lpv);
    let masked = gl.mul(step, mv);
    let s = gl.sum(masked);
    let loss = gl.scale(s, p.norm);
    let lv = gl.value(loss).item();
    let dl = gl.backward(loss);
    let dq = dl
        .var(qv)
        .cloned()
        .unwrap_or_else(|| Tensor::zeros(p.mask.rows(), p.mask.cols()));

    // ∂L/∂ã through each critic, from the share of ∂L/∂min Q it chose.
    let dacts: Vec<Tensor> = critic_graphs
        .par_iter_mut()
        .enumerate()
        .map(|(k, (g, a, q))| {
            let mut seed = Tensor::zeros(dq.rows(), dq.cols());
            for ((s, &d), &c) in seed.data_mut().iter_mut().zip(dq.data()).zip(&chosen) {
                *s += if c == k { d } else { 0.0 };
            }
            let grads = g.backward_with(*q, seed);
            grads
                .var(*a)
                .cloned()
                .unwrap_or_else(|| Tensor::zeros(action.rows(), action.cols()))
        })
        .collect();
    let mut dact = dacts.last().expect("at least one critic").clone();
    for d in dacts.iter().rev().skip(1) {
        for (x, &y) in dact.data_mut().iter_mut().zip(d.data()) {
            *x += y;
        }
    }
    drop(critic_graphs);

    let mut seeds = vec![(act, dact)];
    if let (Some(lp), Some(lpv)) = (log_prob, lpv) {
        if let Some(d) = dl.var(lpv) {
            seeds.push((lp, d.clone()));
        }
    }
    let lp_values = log_prob.map(|lp| ga.value(lp).clone());
    let grad = ga
        .backward_seeded(seeds)
        .take(actor.params())
        .ok_or(NnError::NoGradient {
            len: actor.params().len(),
        });
    (grad, lv, lp_values)
}

/// Sums the parts' actor losses and gradients in part order: the whole batch's loss, its
/// gradient (an error when a part had none) and the samples' log π (SAC), part by part.
pub(crate) fn sum_actor_parts(
    parts: Vec<ActorPart>,
) -> Result<(f32, Vec<f32>, Vec<Tensor>), NnError> {
    let mut grads = Vec::with_capacity(parts.len());
    let mut loss: Option<f32> = None;
    let mut log_probs = Vec::with_capacity(parts.len());
    for (grad, lv, lp) in parts {
        grads.push(grad?);
        loss = Some(loss.map_or(lv, |t| t + lv));
        log_probs.extend(lp);
    }
    Ok((
        loss.unwrap_or(0.0),
        sum_in_order(grads.into_iter()),
        log_probs,
    ))
}
