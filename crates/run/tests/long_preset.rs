//! Contract: `--preset long` is exactly the configuration of the documented ES-SAC run that
//! stays up 60 s (`results/experiments/inner1000-s0`): `quick`, the overlay file
//! `inner_cycles = 1000`, and 895 generations. Only the recorded preset name differs.

mod common;

use common::{options, without_preset_name};
use esrl_run::{AgentKind, EnvKind, Preset, TrainConfig};
use std::path::PathBuf;

#[test]
fn long_is_quick_with_the_documented_overlay() {
    let overlay = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../results/experiments/inner1000-s0/overlay.toml");
    let documented = TrainConfig::resolve(
        AgentKind::EsSac,
        &options(Preset::Quick, Some(overlay), Some(895)),
        Some(0),
    )
    .unwrap();
    let long = TrainConfig::resolve(
        AgentKind::EsSac,
        &options(Preset::Long, None, None),
        Some(0),
    )
    .unwrap();
    assert_eq!(long.preset, Preset::Long);
    assert_eq!(long.env, EnvKind::Walk);
    assert_eq!(long.inner_cycles, 1000);
    assert_eq!(long.generations, 895);
    assert_eq!(without_preset_name(&long), without_preset_name(&documented));
    // And it differs from `quick` where it should.
    let quick = TrainConfig::resolve(
        AgentKind::EsSac,
        &options(Preset::Quick, None, None),
        Some(0),
    )
    .unwrap();
    assert_eq!(quick.inner_cycles, 200);
    assert_eq!(quick.generations, 150);
}
