//! Loops one forward+backward for profiling:
//! `cargo run --release -p esrl-nn --example nn_profile -- actor|critic|mlp_actor|mlp_critic [iters]`
//! (the full SAC update: `cargo run --release -p esrl-agents --example update_profile`).

use esrl_nn::*;
use rand::SeedableRng;

fn main() {
    let mut args = std::env::args().skip(1);
    let what = args.next().unwrap_or_else(|| "actor".into());
    let iters: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(50);
    let (b, t, od, ad) = (256, 8, 43, 6);
    let rec = !what.starts_with("mlp");
    let rows = if rec { b * t } else { b };
    let x = |r: usize, c: usize| {
        Tensor::from_vec(
            r,
            c,
            (0..r * c).map(|i| ((i as f32) * 0.377).sin()).collect(),
        )
    };
    let (obs, act, y) = (x(rows, od), x(rows, ad), x(rows, 1));
    let acfg = if rec {
        ActorConfig::paper()
    } else {
        ActorConfig::feed_forward()
    };
    let ccfg = if rec {
        CriticConfig::paper()
    } else {
        CriticConfig::feed_forward()
    };
    let actor = Actor::new(od, ad, &acfg, 1).unwrap();
    let critic = Critic::new(od, ad, &ccfg, 2).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
    let t0 = std::time::Instant::now();
    let mut fwd = 0.0;
    let mut best = f64::INFINITY;
    for _ in 0..iters {
        let tf = std::time::Instant::now();
        let mut g = Graph::new();
        let o = g.constant(obs.clone());
        let loss = if what.ends_with("actor") {
            let out = actor.forward(&mut g, o, b, None);
            let s = actor.sample(&mut g, &out, &mut rng);
            let a = g.sum_cols(s.action);
            let d = g.sub(s.log_prob, a);
            g.mean(d)
        } else {
            let a = g.constant(act.clone());
            let yv = g.constant(y.clone());
            let q = critic.forward(&mut g, o, a, b, None).q;
            g.mse(q, yv)
        };
        fwd += tf.elapsed().as_secs_f64();
        std::hint::black_box(g.backward(loss));
        best = best.min(tf.elapsed().as_secs_f64() * 1e3);
    }
    let total = t0.elapsed().as_secs_f64() * 1e3 / iters as f64;
    println!(
        "{what}: {total:.3} ms/iter, best {best:.3} (forward {:.3})",
        fwd * 1e3 / iters as f64
    );
}
