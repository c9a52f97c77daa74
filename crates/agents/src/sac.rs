//! One SAC update, top to bottom, under the paper's equation numbers (eqs. 3–7): the soft TD
//! target through the minimum of two target critics, the critics' squared error, the actor's
//! reparameterised loss, the entropy coefficient's step and the Polyak average of the target
//! critics. The batch's parts and their side-by-side execution are
//! [`chunks`](crate::chunks)'; the steps shared with TD3 (burn-in, eq. 4, the target's
//! tail, eq. 7) are in `steps.rs`.

use crate::agent::{Agent, AgentError, UpdateStats};
use crate::chunks::{self, ActorPass, Part};
use crate::replay::SequenceBatch;
use crate::steps::{polyak, soft_target, step_actor, train_critics};
use esrl_nn::{Actor, Graph, Tensor};

/// One SAC update on `batch`.
///
/// Two steps overlap where one does not read what the other writes, which changes no number:
/// the actor's pass at s reads only the actor, so it runs beside the TD targets; the target
/// critics' Polyak step reads only the stepped critics, so it runs beside the actor loss.
pub(crate) fn update(agent: &mut Agent, batch: &SequenceBatch) -> Result<UpdateStats, AgentError> {
    let mut parts = agent.parts(batch);
    // ε for a′ ~ π(·|s′) (eq. 3), then for ã ~ π(·|s) (eq. 5), drawn in that order.
    let eps_next = chunks::normal_noise(&mut agent.rng, &parts, agent.act_dim);
    let eps_now = chunks::normal_noise(&mut agent.rng, &parts, agent.act_dim);
    // Eq. 3 (the TD targets) beside the first half of eq. 5 (ã and log π at s).
    let actor = &agent.actor;
    let (ys, passes) = rayon::join(
        || chunks::each(&parts, eps_next, |p, eps| td_target(agent, p, eps)),
        || chunks::each(&parts, eps_now, |p, eps| actor_sample(actor, p, eps)),
    );
    // Eq. 4: each critic toward y.
    let (critics, opts) = (&mut agent.critics, &mut agent.opt_critics);
    let (critic_loss, q_mean) = train_critics(critics, opts, &mut parts, ys, agent.updates)?;
    // Eq. 5 through the stepped critics, beside eq. 7 for the target critics.
    let tau = agent.cfg.tau as f32;
    let (critics, actor, alpha) = (&agent.critics, &agent.actor, agent.alpha() as f32);
    let (losses, targets) = rayon::join(
        || {
            chunks::each(&parts, passes, |p, pass| {
                // L(π) = 1/M Σ m·(α log π(ã|s) − minₖ Qₖ(s, ã))                       eq. 5
                chunks::through_critics(critics, actor, p, pass, |g, q_min, log_prob| {
                    let alp = g.scale(log_prob.expect("SAC samples ã"), alpha);
                    g.sub(alp, q_min)
                })
            })
        },
        || polyak(&mut agent.critic_targets, critics, tau),
    );
    let (loss, log_probs) = step_actor(agent, losses)?;
    // Eq. 6: α toward the target entropy.
    train_alpha(agent, &log_probs, &parts)?;
    targets?;
    agent.updates += 1;
    Ok(UpdateStats {
        critic_loss,
        actor_loss: Some(f64::from(loss)),
        alpha: Some(agent.alpha()),
        q_mean,
    })
}

/// Eq. 3 for one part, without gradients:
///
/// y = r + γ(1 − d)(minₖ Q̄ₖ(s′, a′) − α log π(a′|s′)),  a′ ~ π(·|s′) with noise `eps`.
fn td_target(agent: &Agent, p: &Part, eps: Tensor) -> Tensor {
    let mut g = Graph::no_grad();
    let o2 = g.constant(p.data.next_obs.clone());
    let out = agent
        .actor
        .forward(&mut g, o2, p.data.batch, p.actor_next.as_ref());
    let s = agent.actor.sample_with_noise(&mut g, &out, eps);
    let alpha = p.data.alpha;
    let entropy: Vec<f32> = g
        .value(s.log_prob)
        .data()
        .iter()
        .map(|lp| -alpha * lp)
        .collect();
    soft_target(agent, p, g.value(s.action), Some(&entropy))
}

/// The first half of eq. 5 for one part, which reads the actor only: ã ~ π(·|s) with noise
/// `eps`, and log π(ã|s).
fn actor_sample<'a>(actor: &'a Actor, p: &Part, eps: Tensor) -> ActorPass<'a> {
    let (mut graph, out) = chunks::actor_graph(actor, p);
    let s = actor.sample_with_noise(&mut graph, &out, eps);
    ActorPass {
        graph,
        act: s.action,
        log_prob: Some(s.log_prob),
    }
}

/// Eq. 6, one Adam step on log α when α is learned:
///
/// L(log α) = −mean(log α · (log π + H̄)) ⇒ ∂L/∂log α = −mean(log π + H̄),
///
/// the mean over the masked steps of the actor loss's samples. A non-finite gradient skips
/// the step.
fn train_alpha(agent: &mut Agent, log_probs: &[Tensor], parts: &[Part]) -> Result<(), AgentError> {
    let Some(entropy) = agent.rules.entropy.filter(|e| e.learn) else {
        return Ok(());
    };
    let mean_lp: f32 = log_probs
        .iter()
        .zip(parts)
        .map(|(lp, p)| {
            lp.data()
                .iter()
                .zip(p.data.mask.data())
                .map(|(l, m)| l * m)
                .sum::<f32>()
        })
        .reduce(|t, s| t + s)
        .unwrap_or(0.0)
        * parts[0].data.norm;
    let grad = [-(mean_lp + entropy.target)];
    if grad[0].is_finite() {
        agent.opt_alpha.step(&mut agent.log_alpha, &grad)?;
    }
    Ok(())
}
