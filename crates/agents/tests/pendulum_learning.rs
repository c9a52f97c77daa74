//! Contract: on Gymnasium's Pendulum-v1 the agents learn within 20,000 environment steps —
//! feed-forward SAC and TD3 reach a mean return ≥ −250 over the last 10 episodes, DDPG ≥ −400,
//! and recurrent (LSTM) SAC ≥ −400. Stable-Baselines3 and CleanRL reach about −150 to −200 in
//! that budget; a random policy scores about −1200.

use esrl_agents::{Agent, Algo, NetConfig, RlConfig, Trainer};
use esrl_nn::{ActorConfig, CriticConfig};
use esrl_sim::{Env, Pendulum};

/// Trains for `episodes` 200-step episodes and returns the mean return of the last 10, on a
/// pool of one thread: the test harness runs the tests side by side, and one rayon pool per
/// test sized to every core would put several threads on each core, where the update's
/// fine-grained parallel steps wait for descheduled threads (the result does not depend on
/// the thread count).
fn train(algo: Algo, nets: &NetConfig, cfg: &RlConfig, seed: u64, episodes: usize) -> f64 {
    let pool = esrl_nn::subnormal::thread_pool(1).unwrap();
    pool.install(|| train_here(algo, nets, cfg, seed, episodes))
}

fn train_here(algo: Algo, nets: &NetConfig, cfg: &RlConfig, seed: u64, episodes: usize) -> f64 {
    let mut env = Pendulum::new();
    let agent = Agent::new(algo, env.obs_dim(), env.act_dim(), nets, cfg, seed).unwrap();
    let mut trainer = Trainer::new(agent, seed);
    let mut returns = Vec::new();
    for _ in 0..episodes {
        let r = trainer.episode(&mut env).unwrap();
        returns.push(r.ret);
    }
    eprintln!(
        "{algo:?} returns: {:?}",
        returns.iter().map(|r| r.round()).collect::<Vec<_>>()
    );
    let tail = &returns[returns.len() - 10..];
    tail.iter().sum::<f64>() / tail.len() as f64
}

fn mlp(width: usize) -> NetConfig {
    NetConfig {
        actor: ActorConfig {
            fc: vec![width, width],
            recurrent: false,
            ..ActorConfig::default()
        },
        critic: CriticConfig {
            obs_fc: vec![],
            act_fc: vec![],
            joint_fc: vec![width, width],
            recurrent: false,
            lstm_hidden: 0,
        },
    }
}

fn pendulum_cfg(algo: Algo) -> RlConfig {
    RlConfig {
        batch_size: 128,
        ..RlConfig::for_algo(algo)
    }
}

#[test]
fn sac_feed_forward_learns_pendulum() {
    let score = train(Algo::Sac, &mlp(128), &pendulum_cfg(Algo::Sac), 1, 100);
    assert!(score >= -250.0, "SAC last-10 mean {score:.1} < -250");
}

#[test]
fn td3_feed_forward_learns_pendulum() {
    let score = train(Algo::Td3, &mlp(128), &pendulum_cfg(Algo::Td3), 1, 100);
    assert!(score >= -250.0, "TD3 last-10 mean {score:.1} < -250");
}

#[test]
fn ddpg_feed_forward_learns_pendulum() {
    let score = train(Algo::Ddpg, &mlp(128), &pendulum_cfg(Algo::Ddpg), 1, 100);
    assert!(score >= -400.0, "DDPG last-10 mean {score:.1} < -400");
}

#[test]
fn sac_recurrent_learns_pendulum() {
    let nets = NetConfig {
        actor: ActorConfig {
            fc: vec![64],
            recurrent: true,
            lstm_hidden: 64,
            ..ActorConfig::default()
        },
        critic: CriticConfig {
            obs_fc: vec![64],
            act_fc: vec![32],
            joint_fc: vec![],
            recurrent: true,
            lstm_hidden: 64,
        },
    };
    let cfg = RlConfig {
        batch_size: 32,
        seq_len: 8,
        burn_in: 4,
        ..RlConfig::default()
    };
    let score = train(Algo::Sac, &nets, &cfg, 1, 100);
    assert!(
        score >= -400.0,
        "recurrent SAC last-10 mean {score:.1} < -400"
    );
}
