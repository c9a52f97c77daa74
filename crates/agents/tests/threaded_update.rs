//! Contract: one gradient update gives the same parameters, bit for bit, whatever the number
//! of threads of the rayon pool it runs in (its large matrix products are split by output
//! rows or columns, never along the summed dimension). Checked after 20 updates of SAC and
//! TD3 with feed-forward 256×256 networks and with LSTM networks, at 1, 2 and 3 threads,
//! with the batch whole and split into chunks (`rl.batch_chunks`). A split batch computes the
//! same losses and gradients as the whole one up to the order of the batch sums.

use esrl_agents::{bench, Agent, Algo, NetConfig};
use esrl_nn::{ActorConfig, CriticConfig, Module};

/// Every parameter of the agent (actor, critics, targets), as bits.
fn bits(agent: &Agent) -> Vec<u32> {
    let mut flat = agent.actor().params().to_flat();
    for c in agent.critics() {
        flat.extend(c.params().to_flat());
    }
    flat.push(agent.alpha() as f32);
    flat.iter().map(|x| x.to_bits()).collect()
}

fn on_threads(
    threads: usize,
    algo: Algo,
    nets: &NetConfig,
    batch: usize,
    chunks: usize,
) -> Vec<u32> {
    let pool = esrl_nn::subnormal::thread_pool(threads).unwrap();
    let (agent, _) = pool
        .install(|| bench::train_on_random_data(algo, nets, 31, 6, batch, chunks, 20))
        .unwrap();
    bits(&agent)
}

/// An LSTM pair of half the paper's width, so the tests stay short; its products (512 rows ×
/// 64–512 columns) are above the split threshold.
fn small_lstm() -> NetConfig {
    NetConfig {
        actor: ActorConfig {
            lstm_hidden: 64,
            ..ActorConfig::default()
        },
        critic: CriticConfig {
            lstm_hidden: 64,
            ..CriticConfig::default()
        },
    }
}

/// The networks both tests train: (name, networks, batch).
fn cases() -> [(&'static str, NetConfig, usize); 2] {
    [
        ("mlp", NetConfig::feed_forward(), 256),
        ("lstm", small_lstm(), 64),
    ]
}

#[test]
fn updates_do_not_depend_on_the_thread_count() {
    for algo in [Algo::Sac, Algo::Td3] {
        for (name, nets, batch) in &cases() {
            for chunks in [1, 3] {
                let one = on_threads(1, algo, nets, *batch, chunks);
                for threads in [2, 3] {
                    assert!(
                        on_threads(threads, algo, nets, *batch, chunks) == one,
                        "{algo:?} {name}, {chunks} chunk(s): 20 updates on {threads} threads \
                         differ from one thread"
                    );
                }
            }
        }
    }
}

/// |a − b| / max(|a|, |b|, 1e-3).
fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(1e-3)
}

#[test]
fn a_batch_split_into_chunks_learns_what_the_whole_batch_learns() {
    // Against the whole batch: every update's losses and mean Q agree to float rounding (the
    // first from the same weights, the later ones after steps that agree), and the first
    // Adam step, ≈ −lr·sign(g) per parameter, moves every parameter the same way, which a
    // chunk with the wrong rows, states, targets or normaliser would not.
    for algo in [Algo::Sac, Algo::Td3] {
        for (name, nets, batch) in &cases() {
            let run = |chunks, updates| {
                bench::train_on_random_data(algo, nets, 31, 6, *batch, chunks, updates).unwrap()
            };
            let (_, whole) = run(1, 20);
            let (_, split) = run(5, 20);
            for (i, (w, s)) in whole.iter().zip(&split).enumerate() {
                let mut pairs = vec![(w.critic_loss, s.critic_loss), (w.q_mean, s.q_mean)];
                if let (Some(a), Some(b)) = (w.actor_loss, s.actor_loss) {
                    pairs.push((a, b));
                }
                for (a, b) in pairs {
                    assert!(
                        rel(a, b) < 1e-5,
                        "{algo:?} {name}: update {i}: whole batch {a}, 5 chunks {b}"
                    );
                }
            }
            let start = bench::train_on_random_data(algo, nets, 31, 6, *batch, 1, 0)
                .unwrap()
                .0;
            let p0 = start.actor().params().to_flat();
            let (a1, _) = run(1, 1);
            let (a5, _) = run(5, 1);
            let (p1, p5) = (a1.actor().params().to_flat(), a5.actor().params().to_flat());
            let differ = p0
                .iter()
                .zip(p1.iter().zip(&p5))
                .filter(|(x0, (x1, x5))| ((*x1 - *x0) - (*x5 - *x0)).abs() > 1e-5)
                .count();
            assert!(
                differ * 1000 <= p0.len(),
                "{algo:?} {name}: the first actor step differs on {differ} of {} parameters",
                p0.len()
            );
        }
    }
}
