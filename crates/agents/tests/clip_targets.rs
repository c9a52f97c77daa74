//! Contract of `rl.clip_targets`: the TD target of eq. 3 is clipped to
//! [(min(r_lo, 0) − e)/(1 − γ), (max(r_hi, 0) + e)/(1 − γ)], r_lo and r_hi the buffer's reward
//! range, e = α·|A|·ln 2 for SAC and 0 for TD3. Checked with target critics made to return
//! values far above the bound: every target is then the upper bound, and the critic loss
//! equals the one computed here from the critics' own Q(s, a) and that bound.

use esrl_agents::{Agent, Algo, NetConfig, ReplayBuffer, RlConfig, Transition};
use esrl_nn::{ActorConfig, CriticConfig, Graph, Tensor};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::HashMap;

const OBS: usize = 3;
const ACT: usize = 2;
const GAMMA: f64 = 0.5;

fn nets() -> NetConfig {
    NetConfig {
        actor: ActorConfig {
            fc: vec![16],
            recurrent: false,
            ..ActorConfig::default()
        },
        critic: CriticConfig {
            obs_fc: vec![16],
            act_fc: vec![16],
            joint_fc: vec![16],
            recurrent: false,
            ..CriticConfig::default()
        },
    }
}

/// 200 transitions with positive observations, rewards in [−1, 0.5), never terminal; and the
/// largest reward pushed.
fn buffer() -> (ReplayBuffer, f32) {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut buf = ReplayBuffer::new(OBS, ACT, 1000);
    let mut r_hi = f32::NEG_INFINITY;
    for _ in 0..200 {
        let obs: Vec<f32> = (0..OBS).map(|_| rng.random_range(0.5..1.5)).collect();
        let next: Vec<f32> = (0..OBS).map(|_| rng.random_range(0.5..1.5)).collect();
        let action: Vec<f32> = (0..ACT).map(|_| rng.random_range(-1.0..1.0)).collect();
        let reward = rng.random_range(-1.0..0.5);
        r_hi = r_hi.max(reward);
        buf.push(Transition {
            obs: &obs,
            action: &action,
            reward,
            next_obs: &next,
            terminated: false,
        });
    }
    (buf, r_hi)
}

/// An agent whose target critics have every parameter set to 0.5: with positive inputs their
/// Q(s′, a′) is in the hundreds, far above a bound of a few units.
fn agent(algo: Algo, clip: bool) -> Agent {
    let cfg = RlConfig {
        gamma: GAMMA,
        clip_targets: clip,
        ..RlConfig::for_algo(algo)
    };
    let mut agent = Agent::new(algo, OBS, ACT, &nets(), &cfg, 9).unwrap();
    let mut tensors: HashMap<String, Vec<f32>> = agent.state_tensors().into_iter().collect();
    for (name, values) in tensors.iter_mut() {
        if name.starts_with("critic") && name.ends_with("_target") {
            values.iter_mut().for_each(|v| *v = 0.5);
        }
    }
    agent.load_state_tensors(&tensors).unwrap();
    agent
}

/// Σₖ 1/(2M) Σ (Qₖ(s, a) − y)² with every target y equal to `y`.
fn loss_against(agent: &Agent, batch: &esrl_agents::SequenceBatch, y: f32) -> f64 {
    let b = batch.batch;
    agent
        .critics()
        .iter()
        .map(|c| {
            let mut g = Graph::no_grad();
            let o = g.constant(Tensor::from_slice(b, OBS, &batch.obs));
            let a = g.constant(Tensor::from_slice(b, ACT, &batch.action));
            let q = c.forward(&mut g, o, a, b, None).q;
            let sq: f64 = g
                .value(q)
                .data()
                .iter()
                .map(|&q| f64::from(q - y).powi(2))
                .sum();
            sq / (2.0 * b as f64)
        })
        .sum()
}

#[test]
fn targets_above_the_bound_are_clipped_to_it() {
    let (buf, r_hi) = buffer();
    assert_eq!(buf.reward_range().map(|r| r.1), Some(r_hi));
    for algo in [Algo::Sac, Algo::Td3] {
        let batch = buf.sample_transitions(&mut ChaCha8Rng::seed_from_u64(2), 64);
        let mut clipped = agent(algo, true);
        let bonus = if clipped.has_entropy() {
            clipped.alpha() * ACT as f64 * std::f64::consts::LN_2
        } else {
            0.0
        };
        let hi = ((f64::from(r_hi.max(0.0)) + bonus) / (1.0 - GAMMA)) as f32;
        let want = loss_against(&clipped, &batch, hi);
        let got = clipped.update(&batch).unwrap().critic_loss;
        assert!(
            (got - want).abs() <= 1e-5 * want,
            "{algo:?}: critic loss {got} against {want} with every target at the bound {hi}"
        );
        // Unclipped, the same update sees targets far above the bound.
        let got_free = agent(algo, false).update(&batch).unwrap().critic_loss;
        assert!(
            got_free > 100.0 * want,
            "{algo:?}: the unclipped loss {got_free} should dwarf the clipped {want}"
        );
    }
}
