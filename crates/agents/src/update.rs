//! The one gradient update of SAC, TD3 and DDPG ([`Agent::update`]): training and every
//! benchmark run this code. What differs between the algorithms was resolved when the agent
//! was built (`Rules` in [`agent`](crate::agent)): the number of critics, the entropy term,
//! target smoothing, the actor's delay.
//!
//! One update on a batch of M masked steps (paper eqs. 3–7; TD3 paper for the deterministic
//! family):
//!
//! 1. burn-in: the networks run the window's first steps without gradients, one step at a
//!    time so the recurrent state can be zeroed where the batch's `reset` says;
//! 2. the target `y` (`td_target`, eq. 3), without gradients;
//! 3. the critic loss (`train_critics`, eq. 4) and one Adam step per critic;
//! 4. every `policy_delay` updates: the actor loss (`train_actor`, eq. 5 or the
//!    deterministic policy gradient), α's step for SAC (`train_alpha`, eq. 6) and
//!    the Polyak update of the targets (`update_targets`, eq. 7).
//!
//! Recurrent networks train on sequence batches from [`crate::ReplayBuffer`]; losses average
//! over the batch's `mask`, so padding past an episode's end never counts.

use crate::agent::{Agent, AgentError, Smoothing, UpdateStats};
use crate::replay::SequenceBatch;
use esrl_nn::{Actor, Adam, Critic, Graph, LstmState, Module, Tensor, Var};
use rand::Rng;
use rand_distr::StandardNormal;
use rayon::prelude::*;

/// The trained part of a batch (its last `seq_len` steps) as tensors, time-major
/// `(len·B, ·)`, with the loss normaliser 1/M.
struct Trained {
    batch: usize,
    obs: Tensor,
    action: Tensor,
    reward: Tensor,
    next_obs: Tensor,
    /// 1 − terminated.
    not_done: Tensor,
    mask: Tensor,
    /// 1/M, M the number of masked (real) steps.
    norm: f32,
    /// α at the start of the update (0 without the entropy term).
    alpha: f32,
    /// The buffer's reward range when the batch was drawn.
    reward_range: (f32, f32),
}

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

/// Recurrent states after burn-in (`None` entries for feed-forward networks).
struct BurnIn {
    actor: Option<LstmState>,
    /// The actor that picks the target action (the target actor of TD3/DDPG), at s′.
    actor_next: Option<LstmState>,
    critics: Vec<Option<LstmState>>,
    critic_targets: Vec<Option<LstmState>>,
}

/// One of the `rl.batch_chunks` fixed parts of a batch that the critic and actor losses run
/// on side by side: batch entries `[b0, b1)` of the trained part, their TD targets and the
/// actor's and critics' states after burn-in. The bounds depend on the batch size and the
/// chunk count only. The loss normaliser stays the whole batch's 1/M, so the chunks' losses
/// and gradients sum to the whole batch's.
struct Chunk {
    part: Trained,
    /// The TD targets (`td_targets`; empty until then).
    y: Tensor,
    actor: Option<LstmState>,
    critics: Vec<Option<LstmState>>,
    /// The state of the actor that picks a′ at s′.
    actor_next: Option<LstmState>,
    critic_targets: Vec<Option<LstmState>>,
}

impl Chunk {
    /// `count` chunks of `part` (one chunk: the whole batch, moved, not copied).
    fn split(part: Trained, st: BurnIn, count: usize) -> Vec<Chunk> {
        let b = part.batch;
        if count <= 1 || b <= 1 {
            return vec![Chunk {
                part,
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
                Chunk {
                    part: Trained {
                        batch: b1 - b0,
                        obs: rows(&part.obs),
                        action: rows(&part.action),
                        reward: rows(&part.reward),
                        next_obs: rows(&part.next_obs),
                        not_done: rows(&part.not_done),
                        mask: rows(&part.mask),
                        ..part
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

/// Adds the chunks' gradients (chunk order) into the first: the whole batch's gradient.
fn sum_in_order(mut parts: impl Iterator<Item = Vec<f32>>) -> Vec<f32> {
    let mut total = parts.next().expect("at least one chunk");
    for g in parts {
        for (t, x) in total.iter_mut().zip(&g) {
            *t += x;
        }
    }
    total
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

/// TD3's target policy smoothing: a′ ← clip(a′ + clip(σ·ε, −c, c), −1, 1), `eps` the
/// standard normal ε of each element.
fn smooth(a: &mut Tensor, s: Smoothing, eps: &[f32]) {
    for (x, e) in a.data_mut().iter_mut().zip(eps) {
        *x = (*x + (s.sd * e).clamp(-s.clip, s.clip)).clamp(-1.0, 1.0);
    }
}

impl Agent {
    /// One gradient update on `batch`: critics; actor, α and targets when due.
    ///
    /// The steps overlap where one does not read what another writes, which changes no
    /// number: the actor's pass at s (the actor loss's first half) reads only the actor, so
    /// it runs beside the TD targets; the target critics' Polyak step reads only the stepped
    /// critics, so it runs beside the actor loss. The noise of both halves is drawn first, in
    /// the order the steps use it (a′ at s′, then ã at s).
    pub fn update(&mut self, batch: &SequenceBatch) -> Result<UpdateStats, AgentError> {
        let part = self.trained_part(batch);
        let st = self.burn_in(batch);
        let mut chunks = Chunk::split(part, st, self.cfg.batch_chunks);
        let actor_due = self.updates.is_multiple_of(self.rules.policy_delay);
        let td_noise = self.chunk_noise(&chunks, self.draws_target_noise());
        let actor_noise = actor_due.then(|| self.chunk_noise(&chunks, self.has_entropy()));
        let actor = &self.actor;
        let (ys, passes) = rayon::join(
            || self.td_targets(&chunks, td_noise),
            || actor_noise.map(|noise| actor_passes(actor, &chunks, noise)),
        );
        for (c, y) in chunks.iter_mut().zip(ys) {
            c.y = y;
        }
        let (critic_loss, q_mean) = Self::train_critics(
            &mut self.critics,
            &mut self.opt_critics,
            &chunks,
            self.updates,
        )?;
        let mut actor_loss = None;
        if let Some(passes) = passes {
            let tau = self.cfg.tau as f32;
            let (critics, actor) = (&self.critics, &self.actor);
            let (parts, targets) = rayon::join(
                || actor_losses(critics, actor, &chunks, passes),
                || polyak(&mut self.critic_targets, critics, tau),
            );
            actor_loss = Some(self.step_actor(parts, &chunks)?);
            targets?;
            if let Some(t) = &mut self.actor_target {
                t.params_mut().polyak_update(self.actor.params(), tau)?;
            }
        }
        self.updates += 1;
        Ok(UpdateStats {
            critic_loss,
            actor_loss,
            alpha: self.has_entropy().then(|| self.alpha()),
            q_mean,
        })
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

    /// Eq. 3, without gradients, into each chunk's `y`:
    ///
    /// y = r + γ(1 − d)(minₖ Q̄ₖ(s′, a′) − α log π(a′|s′)),
    ///
    /// with a′ ~ π(·|s′) for SAC; for TD3/DDPG a′ = μ̄(s′) from the target actor, smoothed
    /// to clip(a′ + clip(ε, −c, c), −1, 1) when `target_noise` > 0, and no entropy term.
    /// `noise` (SAC's ε, TD3's smoothing ε; [`Self::draws_target_noise`]) is drawn for the
    /// whole batch, in the order one pass over the batch draws it, and split like the batch
    /// ([`Self::chunk_noise`]); the chunks run side by side on the rayon pool.
    fn td_targets(&self, chunks: &[Chunk], noise: Vec<Option<Tensor>>) -> Vec<Tensor> {
        chunks
            .par_iter()
            .zip(noise)
            .map(|(c, n)| self.td_target(c, n))
            .collect()
    }

    /// Whether the TD target draws noise: SAC's a′ ~ π(·|s′), TD3's target smoothing.
    fn draws_target_noise(&self) -> bool {
        match &self.actor_target {
            None => true,
            Some(_) => self.rules.smoothing.is_some(),
        }
    }

    /// With `draw`, one standard normal per action dimension for every row of the batch,
    /// drawn from the agent's stream in row order (the order one pass over the whole batch
    /// draws them) and split like the batch into the chunks' shares; without, none.
    fn chunk_noise(&mut self, chunks: &[Chunk], draw: bool) -> Vec<Option<Tensor>> {
        if !draw {
            return vec![None; chunks.len()];
        }
        let b: usize = chunks.iter().map(|c| c.part.batch).sum();
        let rows: usize = chunks.iter().map(|c| c.part.obs.rows()).sum();
        let all: Vec<f32> = (0..rows * self.act_dim)
            .map(|_| self.rng.sample(StandardNormal))
            .collect();
        let all = Tensor::from_vec(rows, self.act_dim, all);
        if chunks.len() == 1 {
            return vec![Some(all)];
        }
        let mut b0 = 0;
        chunks
            .iter()
            .map(|c| {
                let b1 = b0 + c.part.batch;
                let share = batch_rows(&all, b, b0, b1);
                b0 = b1;
                Some(share)
            })
            .collect()
    }

    /// One chunk's TD targets (`td_targets`), `noise` its share of the batch's noise.
    fn td_target(&self, ch: &Chunk, noise: Option<Tensor>) -> Tensor {
        let p = &ch.part;
        let b = p.batch;
        let mut g = Graph::no_grad();
        let o2 = g.constant(p.next_obs.clone());
        let (a2, entropy) = match &self.actor_target {
            None => {
                let out = self.actor.forward(&mut g, o2, b, ch.actor_next.as_ref());
                let eps = noise.expect("SAC draws a′");
                let s = self.actor.sample_with_noise(&mut g, &out, eps);
                let ent: Vec<f32> = g
                    .value(s.log_prob)
                    .data()
                    .iter()
                    .map(|lp| -p.alpha * lp)
                    .collect();
                (g.value(s.action).clone(), Some(ent))
            }
            Some(target) => {
                let out = target.forward(&mut g, o2, b, ch.actor_next.as_ref());
                let det = target.deterministic(&mut g, &out);
                let mut a2 = g.value(det).clone();
                if let (Some(s), Some(eps)) = (self.rules.smoothing, noise) {
                    smooth(&mut a2, s, eps.data());
                }
                (a2, None)
            }
        };
        // The target critics, each on its own graph, side by side on the rayon pool.
        let qs: Vec<Vec<f32>> = self
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
        let gamma = self.cfg.gamma as f32;
        let (lo, hi) = if self.cfg.clip_targets {
            let bonus = p.alpha * self.act_dim as f32 * std::f32::consts::LN_2;
            target_bounds(p.reward_range, gamma, bonus)
        } else {
            (f32::NEG_INFINITY, f32::INFINITY)
        };
        let (r, nd) = (p.reward.data(), p.not_done.data());
        let y = (0..qmin.len())
            .map(|i| {
                let soft = qmin[i] + entropy.as_ref().map_or(0.0, |e| e[i]);
                (r[i] + gamma * nd[i] * soft).clamp(lo, hi)
            })
            .collect();
        Tensor::from_vec(qmin.len(), 1, y)
    }

    /// Eq. 4, summed over the critics, with one Adam step each:
    ///
    /// L(Qₖ) = 1/(2M) Σ m·(Qₖ(s, a) − y)²,
    ///
    /// M the masked steps. Returns the loss and the masked mean of Q₁. Each critic's loss
    /// depends on its own parameters only, and each chunk's share on its own rows, so every
    /// (critic, chunk) pair is its own graph, all side by side on the rayon pool; a critic's
    /// gradient is its chunks' summed in chunk order (one chunk: the same numbers as one
    /// graph of the critics' sum).
    fn train_critics(
        critics: &mut [Critic],
        opts: &mut [Adam],
        chunks: &[Chunk],
        updates: u64,
    ) -> Result<(f64, f64), AgentError> {
        let one = |c: &Critic, ch: &Chunk, state: &Option<LstmState>| {
            let p = &ch.part;
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
        let n = chunks.len();
        let mut pairs: Vec<_> = (0..critics.len() * n)
            .into_par_iter()
            .map(|i| {
                let (k, ch) = (i / n, &chunks[i % n]);
                one(&critics[k], ch, &ch.critics[k])
            })
            .collect();
        // Per critic, its chunks in order: the summed gradient and loss (and Q₁'s mean).
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
            per_critic.push((sum_in_order(grads.into_iter()), loss.unwrap_or(0.0)));
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
            .zip(&mut per_critic)
            .try_for_each(|((c, opt), (grad, _))| opt.step(c.params_mut(), grad).map(drop))?;
        Ok((f64::from(loss), f64::from(q_mean)))
    }
    /// The actor loss through the frozen critics, and one Adam step:
    ///
    /// - SAC (eq. 5): L(π) = 1/M Σ m·(α log π(ã|s) − minₖ Qₖ(s, ã)), ã ~ π(·|s) re-sampled;
    /// - TD3/DDPG: L(μ) = −1/M Σ m·Q₁(s, μ(s)).
    ///
    /// Then α's step (SAC). `parts` are the chunks' losses, actor gradients and log π
    /// ([`actor_losses`]), summed here in chunk order.
    fn step_actor(&mut self, parts: Vec<ActorPart>, chunks: &[Chunk]) -> Result<f64, AgentError> {
        let mut grads = Vec::with_capacity(parts.len());
        let mut loss: Option<f32> = None;
        let mut log_probs = Vec::with_capacity(parts.len());
        for (grad, lv, lp) in parts {
            grads.push(grad?);
            loss = Some(loss.map_or(lv, |t| t + lv));
            log_probs.extend(lp);
        }
        let loss = loss.unwrap_or(0.0);
        if !loss.is_finite() {
            return Err(AgentError::NonFinite {
                what: "actor loss",
                update: self.updates,
            });
        }
        let mut grad = sum_in_order(grads.into_iter());
        self.opt_actor.step(self.actor.params_mut(), &mut grad)?;
        if !log_probs.is_empty() {
            self.train_alpha(&log_probs, chunks)?;
        }
        Ok(f64::from(loss))
    }

    /// Eq. 6, one Adam step on log α when α is learned:
    ///
    /// L(log α) = −mean(log α · (log π + H̄)) ⇒ ∂L/∂log α = −mean(log π + H̄),
    ///
    /// the mean over the masked steps of the actor loss's samples. A non-finite gradient
    /// skips the step.
    fn train_alpha(&mut self, log_probs: &[Tensor], chunks: &[Chunk]) -> Result<(), AgentError> {
        let Some(entropy) = self.rules.entropy.filter(|e| e.learn) else {
            return Ok(());
        };
        let mean_lp: f32 = log_probs
            .iter()
            .zip(chunks)
            .map(|(lp, ch)| {
                lp.data()
                    .iter()
                    .zip(ch.part.mask.data())
                    .map(|(l, m)| l * m)
                    .sum::<f32>()
            })
            .reduce(|t, s| t + s)
            .unwrap_or(0.0)
            * chunks[0].part.norm;
        let mut grad = [-(mean_lp + entropy.target)];
        if grad[0].is_finite() {
            self.opt_alpha.step(&mut self.log_alpha, &mut grad)?;
        }
        Ok(())
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
        let (actor, critics, target_actor, rng) = (
            &self.actor,
            &self.critics,
            self.actor_target.as_ref(),
            &mut self.rng,
        );
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

/// One chunk's share of the actor loss, as [`actor_chunk`] returns it: the actor's
/// gradient, the loss and (SAC) log π of the samples.
type ActorPart = (Result<Vec<f32>, esrl_nn::NnError>, f32, Option<Tensor>);

/// The first half of a chunk's actor loss, which reads the actor only: its graph at s, the
/// action ã it gives (SAC: sampled with the chunk's share of ε) and SAC's log π(ã|s).
struct ActorPass<'a> {
    graph: Graph<'a>,
    act: Var,
    log_prob: Option<Var>,
}

/// Every chunk's [`ActorPass`], side by side on the rayon pool; `noise` is SAC's ε drawn for
/// the whole batch in the order one [`esrl_nn::Actor::sample`] over it draws them, split
/// like the batch ([`Agent::chunk_noise`]), or `None`s for the deterministic actors.
fn actor_passes<'a>(
    actor: &'a Actor,
    chunks: &[Chunk],
    noise: Vec<Option<Tensor>>,
) -> Vec<ActorPass<'a>> {
    chunks
        .par_iter()
        .zip(noise)
        .map(|(ch, eps)| {
            let p = &ch.part;
            let mut graph = Graph::new();
            let ov = graph.constant(p.obs.clone());
            let out = actor.forward(&mut graph, ov, p.batch.max(1), ch.actor.as_ref());
            let (act, log_prob) = match eps {
                Some(eps) => {
                    let s = actor.sample_with_noise(&mut graph, &out, eps);
                    (s.action, Some(s.log_prob))
                }
                None => (actor.deterministic(&mut graph, &out), None),
            };
            ActorPass {
                graph,
                act,
                log_prob,
            }
        })
        .collect()
}

/// The second half of every chunk's actor loss ([`actor_chunk`]), through the stepped
/// critics, side by side on the rayon pool.
fn actor_losses(
    critics: &[Critic],
    actor: &Actor,
    chunks: &[Chunk],
    passes: Vec<ActorPass<'_>>,
) -> Vec<ActorPart> {
    chunks
        .par_iter()
        .zip(passes)
        .map(|(ch, pass)| actor_chunk(critics, actor, ch, pass))
        .collect()
}

/// Eq. 7 for the target critics: θ̄ ← τθ + (1 − τ)θ̄, one target after the other.
fn polyak(targets: &mut [Critic], critics: &[Critic], tau: f32) -> Result<(), AgentError> {
    for (t, c) in targets.iter_mut().zip(critics) {
        t.params_mut().polyak_update(c.params(), tau)?;
    }
    Ok(())
}

/// One chunk's share of the actor loss from its [`ActorPass`]: the actor's gradient, the
/// loss and (SAC) log π. The graph is cut at the action so the critics run side by side on
/// the rayon pool: the actor's graph gave ã (and log π); each critic's own graph gives
/// Qₖ(s, ã) with ã as a leaf; a small graph gives the loss, its value and its gradients
/// with respect to min Qₖ and log π; the minimum's derivative goes to the critic it chose
/// (ties to the first, as [`Graph::minimum`]); each critic's graph turns it into ∂L/∂ã;
/// their sum, last critic first as one graph's reverse pass would add them, and ∂L/∂log π
/// seed the actor's reverse pass. The same numbers as one graph of the whole loss.
fn actor_chunk(critics: &[Critic], actor: &Actor, ch: &Chunk, pass: ActorPass<'_>) -> ActorPart {
    let p = &ch.part;
    let batch = p.batch.max(1);
    let ActorPass {
        graph: mut ga,
        act,
        log_prob,
    } = pass;
    // SAC takes the minimum of its critics; TD3 and DDPG follow Q₁.
    let used = if log_prob.is_some() { critics.len() } else { 1 };
    let action = ga.value(act).clone();

    // Each critic on its own graph: Qₖ(s, ã) with ã a leaf.
    let mut critic_graphs: Vec<_> = critics[..used]
        .par_iter()
        .zip(&ch.critics)
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
    let per_step = match lpv {
        Some(lp) => {
            let alp = gl.scale(lp, p.alpha);
            gl.sub(alp, qv)
        }
        None => gl.neg(qv),
    };
    let masked = gl.mul(per_step, mv);
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
        .ok_or(esrl_nn::NnError::NoGradient {
            len: actor.params().len(),
        });
    (grad, lv, lp_values)
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
