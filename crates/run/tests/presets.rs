//! Every preset resolved for every agent and environment, against the snapshots in
//! `tests/presets/` (the resolved `config.toml` of `esrl train AGENT --env ENV --preset P`).
//!
//! A preset is a TOML file embedded in the binary (`crates/run/presets/`); the snapshots say
//! what those files resolve to, so an edit to a preset, to a default, or to the layering shows
//! up here as the exact keys it changes. After an intended change, refresh the snapshots with
//! `ESRL_BLESS=1 cargo test -p esrl-run --test presets` and review the diff.

use esrl_run::{AgentKind, EnvKind, Preset, TrainConfig};
use std::path::PathBuf;

fn snapshot(agent: AgentKind, env: EnvKind, preset: Preset) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/presets")
        .join(format!(
            "{}-{}-{}.toml",
            preset.name(),
            env.name(),
            agent.name()
        ))
}

#[test]
fn every_preset_resolves_to_its_snapshot() {
    let bless = std::env::var_os("ESRL_BLESS").is_some();
    let mut differ = Vec::new();
    for preset in Preset::ALL {
        for env in EnvKind::ALL {
            for agent in AgentKind::ALL {
                let cfg = TrainConfig::preset(agent, env, preset);
                cfg.validate().unwrap();
                let text = cfg.to_toml().unwrap();
                let path = snapshot(agent, env, preset);
                if bless {
                    std::fs::write(&path, &text).unwrap();
                    continue;
                }
                let want = std::fs::read_to_string(&path)
                    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                let stored = TrainConfig::from_toml(&want).unwrap();
                if stored != cfg {
                    let diff = esrl_run::config::config_differences(&stored, &cfg).unwrap();
                    differ.push(format!("{}: {}", path.display(), diff.join(", ")));
                }
            }
        }
    }
    assert!(differ.is_empty(), "presets changed:\n{}", differ.join("\n"));
}

/// The banner's typical time is the preset's as it comes: a run that changes its budget, its
/// start or its task is told so, with the keys it changes; the seed, the threads, `--until`
/// and a run's own `config.toml` change nothing.
#[test]
fn what_a_run_changes_from_its_preset_is_named() {
    use esrl_run::Overrides;
    let resolve = |o: Overrides| TrainConfig::resolve(AgentKind::EsSac, &o, Some(5)).unwrap();
    let plain = resolve(Overrides {
        threads: Some(2),
        stop_at_walk: Some(false),
        ..Overrides::default()
    });
    assert_eq!(plain.changed_from_preset(), Vec::<String>::new());

    let steps = resolve(Overrides {
        steps: Some(1_500_000),
        ..Overrides::default()
    });
    assert_eq!(steps.changed_from_preset(), ["max_env_steps"]);

    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("downhill.toml");
    std::fs::write(&file, "[walk.perturb]\nslope_range = [-8.0, 0.0]\n").unwrap();
    let task = resolve(Overrides {
        config: Some(file),
        ..Overrides::default()
    });
    let changed = task.changed_from_preset();
    assert!(
        !changed.is_empty() && changed.iter().all(|k| k.starts_with("walk.perturb")),
        "{changed:?}"
    );

    // A run's own config.toml, given back as --config, is the preset as it comes.
    let own = tmp.path().join("config.toml");
    std::fs::write(&own, plain.to_toml().unwrap()).unwrap();
    let again = resolve(Overrides {
        config: Some(own),
        ..Overrides::default()
    });
    assert_eq!(again.changed_from_preset(), Vec::<String>::new());

    // `walker-robust` starts from a walk by design: the walk it is given is its input, as the
    // seed is, so its measured time holds; its budget changed is still named.
    let robust = |steps| {
        resolve(Overrides {
            preset: Preset::WalkerRobust,
            init: Some("/runs/even-s3/best".into()),
            steps,
            ..Overrides::default()
        })
    };
    assert_eq!(robust(None).changed_from_preset(), Vec::<String>::new());
    assert_eq!(
        robust(Some(500_000)).changed_from_preset(),
        ["max_env_steps"]
    );
    // The default given a walk to start from is a fine-tuning run, its time not the preset's.
    let tuned = resolve(Overrides {
        init: Some("/runs/even-s3/best".into()),
        ..Overrides::default()
    });
    assert_eq!(tuned.changed_from_preset(), ["init"]);
}
