//! Contract: a smoke run of each of the six agents from the CLI produces a complete run
//! folder: config.toml, metrics.jsonl and metrics.csv with one row per generation/episode,
//! summary.json with the run-level metrics, and a loadable checkpoint.

mod common;

use common::smoke;

#[test]
fn every_agent_writes_a_complete_run_folder() {
    let tmp = tempfile::tempdir().unwrap();
    for agent in ["es-sac", "es-td3", "es-ddpg", "sac", "td3", "ddpg"] {
        let dir = tmp.path().join(agent);
        smoke(agent, &dir, &[]);
        for f in [
            "config.toml",
            "metrics.jsonl",
            "metrics.csv",
            "summary.json",
        ] {
            assert!(dir.join(f).is_file(), "{agent}: missing {f}");
        }
        for f in [
            "agent.safetensors",
            "actor.safetensors",
            "state.json",
            "config.toml",
            "manifest.json",
        ] {
            assert!(
                dir.join("checkpoint").join(f).is_file(),
                "{agent}: missing checkpoint/{f}"
            );
        }
        let chunks = std::fs::read_dir(dir.join("replay")).unwrap().count();
        assert!(
            chunks >= 1,
            "{agent}: the replay buffer has chunks in RUN/replay/"
        );
        let jsonl = std::fs::read_to_string(dir.join("metrics.jsonl")).unwrap();
        assert_eq!(jsonl.lines().count(), 2, "{agent}: smoke preset has 2 rows");
        let csv = std::fs::read_to_string(dir.join("metrics.csv")).unwrap();
        assert_eq!(csv.lines().count(), 3, "{agent}: header + 2 rows");
        assert!(csv.lines().next().unwrap().contains("curve"));
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap())
                .unwrap();
        for key in [
            "auc",
            "nauc",
            "final_50",
            "best_win_50",
            "episodes_to_target",
        ] {
            assert!(summary.get(key).is_some(), "{agent}: summary lacks {key}");
        }
        assert_eq!(summary["finished"], true);
        let cfg = std::fs::read_to_string(dir.join("config.toml")).unwrap();
        assert!(
            cfg.contains(&format!("agent = \"{agent}\"")),
            "{agent}: config.toml: {cfg}"
        );
    }
}
