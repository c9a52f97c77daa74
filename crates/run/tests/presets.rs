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
