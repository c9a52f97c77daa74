//! The steps of an update that SAC (`sac.rs`) and TD3 (`td3.rs`) share:
//!
//! - burn-in (`Agent::parts`): recurrent networks run the window's first steps without
//!   gradients, one step at a time so the state can be zeroed where the batch's `reset`
//!   says, and the trained part is cut into the parts the losses run on (`chunks.rs`);
//! - the tail of the TD target (eq. 3, [`soft_target`]): the target critics' minimum and
//!   the clip;
//! - the critic loss and one Adam step per critic (eq. 4, [`train_critics`]);
//! - the actor's Adam step ([`step_actor`]);
//! - the Polyak update of the target critics (eq. 7, [`polyak`]).
//!
//! Recurrent networks train on sequence batches from [`crate::ReplayBuffer`]; losses average
//! over the batch's `mask`, so padding past an episode's end never counts.

use crate::agent::{Agent, AgentError};
use crate::chunks::{self, BurnIn, Part, Trained};
use crate::config::Algo;
use crate::replay::SequenceBatch;
use esrl_nn::{Adam, Critic, Graph, LstmState, Module, Tensor};
use rayon::prelude::*;

/// The interval `rl.clip_targets` clips the TD target to: the discounted returns of rewards in
/// `range` (widened to include 0, for episodes that end), plus or minus an entropy bonus
/// `bonus` per step (0 without the entropy term).
pub(crate) fn target_bounds(range: (f32, f32), gamma: f32, bonus: f32) -> (f32, f32) {
    let horizon = 1.0 / (1.0 - gamma);
    (
        (range.0.min(0.0) - bonus) * horizon,
        (range.1.max(0.0) + bonus) * horizon,
    )
}

/// Rows `[t0·B, t1·B)` of a time-major `(W·B, cols)` array as a tensor.
fn steps(data: &[f32], batch: usize, cols: usize, t0: usize, t1: usize) -> Tensor {
    Tensor::from_slice(
        (t1 - t0) * batch,
        cols,
        &data[t0 * batch * cols..t1 * batch * cols],
    )
}

/// Zeroes the rows of `state` whose `reset` flag is set.
fn apply_resets(state: &mut Option<LstmState>, reset: &[bool]) {
    let Some(s) = state else { return };
    let h = s.h.cols();
    for (b, _) in reset.iter().enumerate().filter(|(_, &r)| r) {
        s.h.data_mut()[b * h..(b + 1) * h].fill(0.0);
        s.c.data_mut()[b * h..(b + 1) * h].fill(0.0);
    }
}

impl Agent {
    /// The batch's trained part with every network's state after burn-in, cut into the
    /// `rl.batch_chunks` parts the losses run on ([`chunks`]).
    pub(crate) fn parts(&mut self, batch: &SequenceBatch) -> Vec<Part> {
        let data = self.trained_part(batch);
        let states = self.burn_in(batch);
        chunks::split(data, states, self.cfg.batch_chunks)
    }

    fn trained_part(&self, batch: &SequenceBatch) -> Trained {
        let b = batch.batch;
        let (o, a) = (self.obs_dim, self.act_dim);
        let (burn, w) = (batch.burn_in, batch.window);
        let n_masked: f32 = batch.mask[burn * b..].iter().sum();
        Trained {
            batch: b,
            obs: steps(&batch.obs, b, o, burn, w),
            action: steps(&batch.action, b, a, burn, w),
            reward: steps(&batch.reward, b, 1, burn, w),
            next_obs: steps(&batch.next_obs, b, o, burn, w),
            not_done: Tensor::from_vec(
                (w - burn) * b,
                1,
                batch.terminated[burn * b..]
                    .iter()
                    .map(|d| 1.0 - d)
                    .collect(),
            ),
            mask: steps(&batch.mask, b, 1, burn, w),
            norm: 1.0 / n_masked.max(1.0),
            alpha: self.alpha() as f32,
            reward_range: batch.reward_range,
        }
    }

    /// Runs the burn-in prefix without gradients and returns every network's state at the
    /// start of the trained part. Each network runs its own prefix (on the rayon pool, side
    /// by side): the actor, each critic, the actor that picks a′ at s′ (drawing its samples
    /// from the agent's stream, step by step as before), then each target critic on those a′.
    fn burn_in(&mut self, batch: &SequenceBatch) -> BurnIn {
        let b = batch.batch;
        let (o, a) = (self.obs_dim, self.act_dim);
        let zero = BurnIn {
            actor: self.actor.zero_state(b),
            actor_next: self.actor.zero_state(b),
            critics: self.critics.iter().map(|c| c.zero_state(b)).collect(),
            critic_targets: self
                .critic_targets
                .iter()
                .map(|c| c.zero_state(b))
                .collect(),
        };
        let recurrent = zero.actor.is_some() || zero.critics.iter().any(Option::is_some);
        if !recurrent {
            return zero;
        }
        let burn = batch.burn_in;
        let reset = |t: usize| &batch.reset[t * b..(t + 1) * b];
        // One network's prefix: its state after the resets of steps 0..=burn and the
        // forwards of steps 0..burn, `forward` giving the next state.
        let prefix =
            |mut state: Option<LstmState>,
             forward: &mut dyn FnMut(usize, Option<&LstmState>) -> Option<LstmState>| {
                for t in 0..=burn {
                    apply_resets(&mut state, reset(t));
                    if t == burn {
                        break;
                    }
                    state = forward(t, state.as_ref());
                }
                state
            };
        let obs = |t: usize| steps(&batch.obs, b, o, t, t + 1);
        let act = |t: usize| steps(&batch.action, b, a, t, t + 1);
        let next_obs = |t: usize| steps(&batch.next_obs, b, o, t, t + 1);

        let BurnIn {
            actor: actor0,
            actor_next: next0,
            critics: critics0,
            critic_targets: targets0,
        } = zero;
        // SAC samples a′ from the actor; TD3 and DDPG take the target actor's μ̄(s′).
        let target_actor = match self.algo {
            Algo::Sac => None,
            Algo::Td3 | Algo::Ddpg => Some(
                self.actor_target
                    .as_ref()
                    .expect("TD3 and DDPG agents are built with a target actor"),
            ),
        };
        let (actor, critics, rng) = (&self.actor, &self.critics, &mut self.rng);
        // The actor that picks a′, with the a′ of every burn-in step.
        let next_chain = || {
            let mut picks = Vec::with_capacity(burn);
            let next_actor = target_actor.unwrap_or(actor);
            let state = prefix(next0, &mut |t, s| {
                let mut g = Graph::no_grad();
                let o2 = g.constant(next_obs(t));
                let out = next_actor.forward(&mut g, o2, b, s);
                let a2 = match target_actor {
                    None => actor.sample(&mut g, &out, rng).action,
                    Some(target) => target.deterministic(&mut g, &out),
                };
                picks.push(g.take_value(a2));
                out.state
            });
            (state, picks)
        };
        let own_chains = || {
            let actor_state = || {
                prefix(actor0, &mut |t, s| {
                    let mut g = Graph::no_grad();
                    let ov = g.constant(obs(t));
                    actor.forward(&mut g, ov, b, s).state
                })
            };
            let critic_states = || -> Vec<Option<LstmState>> {
                critics
                    .par_iter()
                    .zip(critics0)
                    .map(|(c, s0)| {
                        prefix(s0, &mut |t, s| {
                            let mut g = Graph::no_grad();
                            let (ov, av) = (g.constant(obs(t)), g.constant(act(t)));
                            c.forward(&mut g, ov, av, b, s).state
                        })
                    })
                    .collect()
            };
            rayon::join(actor_state, critic_states)
        };
        let ((actor_next, picks), (actor, critics)) = rayon::join(next_chain, own_chains);
        let critic_targets = self
            .critic_targets
            .par_iter()
            .zip(targets0)
            .map(|(c, s0)| {
                prefix(s0, &mut |t, s| {
                    let mut g = Graph::no_grad();
                    let (o2, a2) = (g.constant(next_obs(t)), g.constant(picks[t].clone()));
                    c.forward(&mut g, o2, a2, b, s).state
                })
            })
            .collect();
        BurnIn {
            actor,
            actor_next,
            critics,
            critic_targets,
        }
    }
}

/// The tail of eq. 3 that SAC and TD3 share, for one part, without gradients:
///
/// y = clip(r + γ(1 − d)(minₖ Q̄ₖ(s′, a′) + e)),
///
/// `a2` the actions a′ at s′, `entropy` SAC's e = −α log π(a′|s′) per step (none for TD3),
/// the clip to [`target_bounds`] when `rl.clip_targets` is on.
pub(crate) fn soft_target(
    agent: &Agent,
    ch: &Part,
    a2: &Tensor,
    entropy: Option<&[f32]>,
) -> Tensor {
    let p = &ch.data;
    let b = p.batch;
    // The target critics, each on its own graph, side by side on the rayon pool.
    let qs: Vec<Vec<f32>> = agent
        .critic_targets
        .par_iter()
        .zip(&ch.critic_targets)
        .map(|(c, state)| {
            let mut g = Graph::no_grad();
            let (o2, a2) = (g.constant(p.next_obs.clone()), g.constant(a2.clone()));
            let q = c.forward(&mut g, o2, a2, b, state.as_ref()).q;
            g.value(q).data().to_vec()
        })
        .collect();
    let qmin = qs
        .into_iter()
        .reduce(|m, q| m.iter().zip(&q).map(|(x, y)| x.min(*y)).collect())
        .unwrap_or_default();
    let gamma = agent.cfg.gamma as f32;
    let (lo, hi) = if agent.cfg.clip_targets {
        let bonus = p.alpha * agent.act_dim as f32 * std::f32::consts::LN_2;
        target_bounds(p.reward_range, gamma, bonus)
    } else {
        (f32::NEG_INFINITY, f32::INFINITY)
    };
    let (r, nd) = (p.reward.data(), p.not_done.data());
    let y = (0..qmin.len())
        .map(|i| {
            let soft = qmin[i] + entropy.map_or(0.0, |e| e[i]);
            (r[i] + gamma * nd[i] * soft).clamp(lo, hi)
        })
        .collect();
    Tensor::from_vec(qmin.len(), 1, y)
}

/// Eq. 4 toward the TD targets `ys` (one per part, kept in the parts), summed over the
/// critics, with one Adam step each:
///
/// L(Qₖ) = 1/(2M) Σ m·(Qₖ(s, a) − y)²,
///
/// M the masked steps. Returns the loss and the masked mean of Q₁. Each critic's loss
/// depends on its own parameters only, and each part's share on its own rows, so every
/// (critic, part) pair is its own graph, all side by side on the rayon pool; a critic's
/// gradient is its parts' summed in part order (one part: the same numbers as one
/// graph of the critics' sum).
pub(crate) fn train_critics(
    critics: &mut [Critic],
    opts: &mut [Adam],
    parts: &mut [Part],
    ys: Vec<Tensor>,
    updates: u64,
) -> Result<(f64, f64), AgentError> {
    for (p, y) in parts.iter_mut().zip(ys) {
        p.y = y;
    }
    let parts = &*parts;
    let one = |c: &Critic, ch: &Part, state: &Option<LstmState>| {
        let p = &ch.data;
        let mut g = Graph::new();
        let (ov, av, yv, mv) = (
            g.constant(p.obs.clone()),
            g.constant(p.action.clone()),
            g.constant(ch.y.clone()),
            g.constant(p.mask.clone()),
        );
        let q = c.forward(&mut g, ov, av, p.batch, state.as_ref()).q;
        let q_sum = g
            .value(q)
            .data()
            .iter()
            .zip(p.mask.data())
            .map(|(q, m)| q * m)
            .sum::<f32>()
            * p.norm;
        let d = g.sub(q, yv);
        let d2 = g.square(d);
        let d2 = g.mul(d2, mv);
        let s = g.sum(d2);
        let l = g.scale(s, 0.5 * p.norm);
        let lv = g.value(l).item();
        let grad = g
            .backward(l)
            .take(c.params())
            .ok_or(esrl_nn::NnError::NoGradient {
                len: c.params().len(),
            });
        (grad, lv, q_sum)
    };
    let n = parts.len();
    let mut pairs: Vec<_> = (0..critics.len() * n)
        .into_par_iter()
        .map(|i| {
            let (k, ch) = (i / n, &parts[i % n]);
            one(&critics[k], ch, &ch.critics[k])
        })
        .collect();
    // Per critic, its parts in order: the summed gradient and loss (and Q₁'s mean).
    let mut per_critic = Vec::with_capacity(critics.len());
    let mut q_mean = 0.0;
    for k in 0..critics.len() {
        let mut grads = Vec::with_capacity(n);
        let (mut loss, mut q_sum) = (None, None);
        for (grad, lv, qs) in pairs.drain(..n) {
            grads.push(grad?);
            loss = Some(loss.map_or(lv, |t: f32| t + lv));
            q_sum = Some(q_sum.map_or(qs, |t: f32| t + qs));
        }
        if k == 0 {
            q_mean = q_sum.unwrap_or(0.0);
        }
        per_critic.push((chunks::sum_in_order(grads.into_iter()), loss.unwrap_or(0.0)));
    }
    let loss = per_critic
        .iter()
        .map(|r| r.1)
        .reduce(|t, l| t + l)
        .expect("at least one critic");
    if !loss.is_finite() {
        return Err(AgentError::NonFinite {
            what: "critic loss",
            update: updates,
        });
    }
    critics
        .par_iter_mut()
        .zip(opts)
        .zip(&per_critic)
        .try_for_each(|((c, opt), (grad, _))| opt.step(c.params_mut(), grad).map(drop))?;
    for (grad, _) in per_critic {
        esrl_nn::recycle(grad);
    }
    Ok((f64::from(loss), f64::from(q_mean)))
}

/// The actor's Adam step on its loss: the parts' losses and gradients summed in part order
/// ([`chunks::sum_actor_parts`]), a non-finite loss refused. Returns the loss and (SAC) the
/// samples' log π, part by part.
pub(crate) fn step_actor(
    agent: &mut Agent,
    losses: Vec<chunks::ActorPart>,
) -> Result<(f32, Vec<Tensor>), AgentError> {
    let (loss, grad, log_probs) = chunks::sum_actor_parts(losses)?;
    if !loss.is_finite() {
        return Err(AgentError::NonFinite {
            what: "actor loss",
            update: agent.updates,
        });
    }
    agent.opt_actor.step(agent.actor.params_mut(), &grad)?;
    esrl_nn::recycle(grad);
    Ok((loss, log_probs))
}

/// Eq. 7 for the target critics: θ̄ ← τθ + (1 − τ)θ̄, one target after the other.
pub(crate) fn polyak(
    targets: &mut [Critic],
    critics: &[Critic],
    tau: f32,
) -> Result<(), AgentError> {
    for (t, c) in targets.iter_mut().zip(critics) {
        t.params_mut().polyak_update(c.params(), tau)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::target_bounds;

    #[test]
    fn target_bounds_by_hand() {
        // γ = 0.9: a horizon of 10 steps.
        let (lo, hi) = target_bounds((-2.0, 3.0), 0.9, 0.0);
        assert!(
            (lo + 20.0).abs() < 1e-4 && (hi - 30.0).abs() < 1e-4,
            "{lo} {hi}"
        );
        // Rewards all positive: an episode that ends at once returns 0, so 0 stays inside.
        let (lo, hi) = target_bounds((1.0, 2.0), 0.9, 0.0);
        assert!(lo.abs() < 1e-4 && (hi - 20.0).abs() < 1e-4, "{lo} {hi}");
        // An entropy bonus of 0.5 per step widens both sides by 5.
        let (lo, hi) = target_bounds((-1.0, -0.5), 0.9, 0.5);
        assert!(
            (lo + 15.0).abs() < 1e-4 && (hi - 5.0).abs() < 1e-4,
            "{lo} {hi}"
        );
    }
}
