//! One TD3 update, top to bottom (Fujimoto et al. 2018, in the paper's equation numbers where
//! they apply): the TD target through the minimum of the target critics at the target
//! actor's smoothed action, the critics' squared error, and every `policy_delay` updates the
//! deterministic policy gradient through Q₁ and the Polyak average of every target. DDPG is
//! this update with one critic, no smoothing and no delay ([`crate::RlConfig::for_algo`]),
//! as Stable-Baselines3 has it. The batch's parts and their side-by-side execution are
//! [`chunks`](crate::chunks)'; the steps shared with SAC are in `steps.rs`.

use crate::agent::{Agent, AgentError, Smoothing, UpdateStats};
use crate::chunks::{self, ActorPass, Part};
use crate::replay::SequenceBatch;
use crate::steps::{polyak, soft_target, step_actor, train_critics};
use esrl_nn::{Actor, Graph, Module, Tensor};

/// One TD3/DDPG update on `batch`.
///
/// Two steps overlap where one does not read what the other writes, which changes no number:
/// the actor's pass at s reads only the actor, so it runs beside the TD targets; the target
/// critics' Polyak step reads only the stepped critics, so it runs beside the actor loss.
pub(crate) fn update(agent: &mut Agent, batch: &SequenceBatch) -> Result<UpdateStats, AgentError> {
    let mut parts = agent.parts(batch);
    let actor_due = agent.updates.is_multiple_of(agent.rules.policy_delay);
    // ε of the target policy smoothing (eq. 3's a′), when it is on.
    let smoothing = agent.rules.smoothing;
    let eps_next = match smoothing {
        Some(_) => chunks::normal_noise(&mut agent.rng, &parts, agent.act_dim)
            .into_iter()
            .map(Some)
            .collect(),
        None => vec![None; parts.len()],
    };
    // Eq. 3 (the TD targets) beside the first half of the actor loss (μ(s)), when due.
    let actor = &agent.actor;
    let (ys, passes) = rayon::join(
        || chunks::each(&parts, eps_next, |p, eps| td_target(agent, p, eps)),
        || actor_due.then(|| chunks::each_part(&parts, |p| act(actor, p))),
    );
    // Eq. 4: each critic toward y.
    let (critics, opts) = (&mut agent.critics, &mut agent.opt_critics);
    let (critic_loss, q_mean) = train_critics(critics, opts, &mut parts, ys, agent.updates)?;
    let mut actor_loss = None;
    if let Some(passes) = passes {
        // The deterministic policy gradient through Q₁, beside eq. 7 for the target critics.
        let tau = agent.cfg.tau as f32;
        let (critics, actor) = (&agent.critics, &agent.actor);
        let (losses, targets) = rayon::join(
            || {
                chunks::each(&parts, passes, |p, pass| {
                    // L(μ) = −1/M Σ m·Q₁(s, μ(s))
                    chunks::through_critics(&critics[..1], actor, p, pass, |g, q1, _| g.neg(q1))
                })
            },
            || polyak(&mut agent.critic_targets, critics, tau),
        );
        let (loss, _) = step_actor(agent, losses)?;
        targets?;
        // Eq. 7 for the target actor.
        let target = agent
            .actor_target
            .as_mut()
            .expect("TD3 and DDPG agents are built with a target actor");
        target
            .params_mut()
            .polyak_update(agent.actor.params(), tau)?;
        actor_loss = Some(f64::from(loss));
    }
    agent.updates += 1;
    Ok(UpdateStats {
        critic_loss,
        actor_loss,
        alpha: None,
        q_mean,
    })
}

/// The target actor μ̄ (TD3 and DDPG have one).
fn target_actor(agent: &Agent) -> &Actor {
    agent
        .actor_target
        .as_ref()
        .expect("TD3 and DDPG agents are built with a target actor")
}

/// Eq. 3 for one part, without gradients, in TD3's form (no entropy term):
///
/// y = r + γ(1 − d) minₖ Q̄ₖ(s′, a′),  a′ = clip(μ̄(s′) + clip(ε, −c, c), −1, 1),
///
/// the smoothing only when `eps` is given.
fn td_target(agent: &Agent, p: &Part, eps: Option<Tensor>) -> Tensor {
    let target = target_actor(agent);
    let mut g = Graph::no_grad();
    let o2 = g.constant(p.data.next_obs.clone());
    let out = target.forward(&mut g, o2, p.data.batch, p.actor_next.as_ref());
    let det = target.deterministic(&mut g, &out);
    let mut a2 = g.value(det).clone();
    if let (Some(s), Some(eps)) = (agent.rules.smoothing, eps) {
        smooth(&mut a2, s, eps.data());
    }
    soft_target(agent, p, &a2, None)
}

/// TD3's target policy smoothing: a′ ← clip(a′ + clip(σ·ε, −c, c), −1, 1), `eps` the
/// standard normal ε of each element.
fn smooth(a: &mut Tensor, s: Smoothing, eps: &[f32]) {
    for (x, e) in a.data_mut().iter_mut().zip(eps) {
        *x = (*x + (s.sd * e).clamp(-s.clip, s.clip)).clamp(-1.0, 1.0);
    }
}

/// The first half of the actor loss for one part, which reads the actor only: μ(s).
fn act<'a>(actor: &'a Actor, p: &Part) -> ActorPass<'a> {
    let (mut graph, out) = chunks::actor_graph(actor, p);
    ActorPass {
        act: actor.deterministic(&mut graph, &out),
        graph,
        log_prob: None,
    }
}
