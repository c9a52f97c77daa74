//! Contract: `rl.mirror` ([`mirror_batch`]) replaces exactly the odd-numbered windows of a
//! batch (1, 3, …) by their mirror images, at every step of a sequence window and in
//! observations, next observations and actions alike, and leaves rewards, ends, masks and
//! the even windows as drawn.

use esrl_agents::train::mirror_batch;
use esrl_agents::{ReplayBuffer, Transition};
use esrl_sim::{Env, GaitClock, WalkConfig, WalkEnv};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

#[test]
fn odd_windows_are_mirrored_and_nothing_else_changes() {
    let env = WalkEnv::new(WalkConfig {
        gait_clock: Some(GaitClock::default()),
        ..WalkConfig::default()
    })
    .unwrap();
    let mirror = env.mirror().unwrap();
    let (o, a) = (env.obs_dim(), env.act_dim());
    let mut buffer = ReplayBuffer::new(o, a, 1000);
    for ep in 0..3 {
        for t in 0..40 {
            let v = |k: usize, salt: f32| ((k as f32 + 1.0) * 0.37 + salt).sin();
            let obs: Vec<f32> = (0..o).map(|k| v(k, (ep * 100 + t) as f32)).collect();
            let next: Vec<f32> = (0..o).map(|k| v(k, (ep * 100 + t) as f32 + 0.5)).collect();
            let action: Vec<f32> = (0..a).map(|k| v(k, t as f32 * 0.1)).collect();
            buffer.push(Transition {
                obs: &obs,
                action: &action,
                reward: t as f32,
                next_obs: &next,
                terminated: t == 39,
            });
        }
        buffer.end_episode();
    }
    let drawn = buffer.sample_sequences(&mut ChaCha8Rng::seed_from_u64(5), 6, 4, 2);
    let mut batch = drawn.clone();
    mirror_batch(&mut batch, &mirror);
    for t in 0..batch.window {
        for b in 0..batch.batch {
            let r = batch.row(t, b);
            let (obs, next, act) = (
                &drawn.obs[r * o..(r + 1) * o],
                &drawn.next_obs[r * o..(r + 1) * o],
                &drawn.action[r * a..(r + 1) * a],
            );
            let want = |x: &[f32], is_obs: bool| -> Vec<f32> {
                match (b % 2 == 1, is_obs) {
                    (false, _) => x.to_vec(),
                    (true, true) => mirror.obs(x),
                    (true, false) => mirror.action(x),
                }
            };
            assert_eq!(
                &batch.obs[r * o..(r + 1) * o],
                want(obs, true),
                "obs {t},{b}"
            );
            assert_eq!(&batch.next_obs[r * o..(r + 1) * o], want(next, true));
            assert_eq!(&batch.action[r * a..(r + 1) * a], want(act, false));
        }
    }
    assert_ne!(batch.obs, drawn.obs);
    assert_eq!(batch.reward, drawn.reward);
    assert_eq!(batch.terminated, drawn.terminated);
    assert_eq!(batch.mask, drawn.mask);
}
