//! Contract: with `updates_per_step = r`, a generation runs round(r × its environment steps)
//! inner updates instead of the fixed `inner_cycles`, so the update-to-data ratio holds as
//! episodes lengthen.

mod common;

use common::hybrid;
use esrl_agents::Algo;
use esrl_es::EsConfig;

#[test]
fn inner_updates_follow_the_steps_collected() {
    let mut h = hybrid(Algo::Td3, EsConfig::default(), 7);
    h.set_updates_per_step(Some(0.013));
    for _ in 0..3 {
        let (steps, updates) = (h.trainer().env_steps(), h.trainer().agent().updates());
        let r = h.step().unwrap();
        let collected = r.env_steps - steps;
        assert_eq!(collected, 6 * 200, "six pendulum episodes of 200 steps");
        assert_eq!(
            h.trainer().agent().updates() - updates,
            (0.013 * collected as f64).round() as u64,
            "16 updates, not the fixed 7"
        );
    }
}
