//! Contract: one gradient update gives the same parameters, bit for bit, whatever the number
//! of threads of the rayon pool it runs in (its large matrix products are split by output
//! rows or columns, never along the summed dimension). Checked after 20 updates of SAC and
//! TD3 with feed-forward 256×256 networks and with LSTM networks, at 1, 2 and 3 threads.

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

fn on_threads(threads: usize, algo: Algo, nets: &NetConfig, batch: usize) -> Vec<u32> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let agent = pool
        .install(|| bench::train_on_random_data(algo, nets, 31, 6, batch, 20))
        .unwrap();
    bits(&agent)
}

#[test]
fn updates_do_not_depend_on_the_thread_count() {
    // An LSTM pair of half the paper's width, so the test stays short; its products (512
    // rows × 64–512 columns) are above the split threshold.
    let lstm = NetConfig {
        actor: ActorConfig {
            lstm_hidden: 64,
            ..ActorConfig::default()
        },
        critic: CriticConfig {
            lstm_hidden: 64,
            ..CriticConfig::default()
        },
    };
    let cases = [("mlp", NetConfig::feed_forward(), 256), ("lstm", lstm, 64)];
    for algo in [Algo::Sac, Algo::Td3] {
        for (name, nets, batch) in &cases {
            let one = on_threads(1, algo, nets, *batch);
            for threads in [2, 3] {
                assert!(
                    on_threads(threads, algo, nets, *batch) == one,
                    "{algo:?} {name}: 20 updates on {threads} threads differ from one thread"
                );
            }
        }
    }
}
