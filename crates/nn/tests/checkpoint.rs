//! Contract: networks round-trip through safetensors files with stable, PyTorch-shaped tensor
//! names (several networks per file under prefixes); malformed, truncated, mismatched or
//! non-finite files give typed errors, never panics, and leave the parameters untouched.

use esrl_nn::*;
use std::path::Path;

fn actor(seed: u64) -> Actor {
    Actor::new(43, 6, &ActorConfig::paper(), seed).unwrap()
}

fn outputs(a: &Actor) -> Vec<f32> {
    let mut g = Graph::no_grad();
    let o = g.constant(Tensor::from_vec(
        2 * 3,
        43,
        (0..6 * 43).map(|i| (i as f32 * 0.1).sin()).collect(),
    ));
    let out = a.forward(&mut g, o, 3, None);
    g.value(out.mean)
        .data()
        .iter()
        .chain(g.value(out.std).data())
        .copied()
        .collect()
}

#[test]
fn round_trip_restores_parameters_and_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ckpt.safetensors");
    let a = actor(1);
    let c1 = Critic::new(43, 6, &CriticConfig::paper(), 2).unwrap();
    save_params(&path, &[("actor.", a.params()), ("critic1.", c1.params())]).unwrap();
    let mut b = actor(99);
    let mut c2 = Critic::new(43, 6, &CriticConfig::paper(), 98).unwrap();
    assert_ne!(a.params().as_slice(), b.params().as_slice());
    load_params(
        &path,
        &mut [("actor.", b.params_mut()), ("critic1.", c2.params_mut())],
    )
    .unwrap();
    assert_eq!(a.params().as_slice(), b.params().as_slice());
    assert_eq!(c1.params().as_slice(), c2.params().as_slice());
    assert_eq!(outputs(&a), outputs(&b));
    assert!(!dir.path().join("ckpt.safetensors.tmp").exists());
}

#[test]
fn names_and_shapes_are_the_documented_ones() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.safetensors");
    save_params(
        &path,
        &[
            ("", actor(1).params()),
            (
                "q.",
                Critic::new(43, 6, &CriticConfig::paper(), 2)
                    .unwrap()
                    .params(),
            ),
        ],
    )
    .unwrap();
    let t = load_tensors(&path).unwrap();
    let expect: &[(&str, &[usize])] = &[
        ("fc.0.weight", &[256, 43]),
        ("fc.0.bias", &[256]),
        ("lstm.weight_ih", &[400, 256]),
        ("lstm.weight_hh", &[400, 100]),
        ("lstm.bias", &[400]),
        ("mean.weight", &[6, 100]),
        ("mean.bias", &[6]),
        ("std.weight", &[6, 100]),
        ("std.bias", &[6]),
        ("q.obs_fc.0.weight", &[128, 43]),
        ("q.obs_fc.0.bias", &[128]),
        ("q.act_fc.0.weight", &[128, 6]),
        ("q.act_fc.0.bias", &[128]),
        ("q.lstm.weight_ih", &[448, 256]),
        ("q.lstm.weight_hh", &[448, 112]),
        ("q.lstm.bias", &[448]),
        ("q.q.weight", &[1, 112]),
        ("q.q.bias", &[1]),
    ];
    assert_eq!(t.len(), expect.len(), "{:?}", t.keys().collect::<Vec<_>>());
    for (name, shape) in expect {
        assert_eq!(t[*name].shape, *shape, "{name}");
    }
    // Raw bytes: little-endian f32 at the offsets the header gives (what NumPy reads).
    let a = actor(1);
    assert_eq!(t["lstm.bias"].data, a.params().tensor("lstm.bias").unwrap());
}

fn write(path: &Path, bytes: &[u8]) {
    std::fs::write(path, bytes).unwrap();
}

/// A one-tensor safetensors file written by hand.
fn raw_file(dtype: &str, shape: &[usize], data: &[u8]) -> Vec<u8> {
    let header = format!(
        r#"{{"fc.0.weight":{{"dtype":"{dtype}","shape":{shape:?},"data_offsets":[0,{}]}}}}"#,
        data.len()
    );
    let mut out = (header.len() as u64).to_le_bytes().to_vec();
    out.extend(header.as_bytes());
    out.extend(data);
    out
}

#[test]
fn malformed_files_give_typed_errors_and_change_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("good.safetensors");
    save_params(&good, &[("", actor(1).params())]).unwrap();
    let bytes = std::fs::read(&good).unwrap();
    let mut target = actor(5);
    let before = target.params().to_flat();
    let p = |name: &str| dir.path().join(name);

    let check = |path: &Path, target: &mut Actor, want: &str| {
        let err = load_params(path, &mut [("", target.params_mut())]).unwrap_err();
        let msg = err.to_string();
        let kind = format!("{err:?}");
        assert!(
            kind.starts_with(want),
            "{path:?}: expected {want}, got {kind}"
        );
        assert!(
            msg.contains(&path.display().to_string()),
            "error must name the file: {msg}"
        );
    };

    check(&p("missing.safetensors"), &mut target, "Io");
    write(&p("empty"), &[]);
    check(&p("empty"), &mut target, "Format");
    write(&p("garbage"), b"definitely not a safetensors file at all");
    check(&p("garbage"), &mut target, "Format");
    write(&p("huge_header"), &u64::MAX.to_le_bytes());
    check(&p("huge_header"), &mut target, "Format");
    write(&p("truncated"), &bytes[..bytes.len() / 2]);
    check(&p("truncated"), &mut target, "Format");
    write(
        &p("bad_json"),
        &[
            8, 0, 0, 0, 0, 0, 0, 0, b'{', b'{', b'{', b'{', b'{', b'{', b'{', b'{',
        ],
    );
    check(&p("bad_json"), &mut target, "Format");
    write(&p("f64"), &raw_file("F64", &[1], &1.0f64.to_le_bytes()));
    check(&p("f64"), &mut target, "DtypeMismatch");
    write(&p("shape"), &raw_file("F32", &[1], &1.0f32.to_le_bytes()));
    check(&p("shape"), &mut target, "ShapeMismatch");
    let critic = dir.path().join("critic.safetensors");
    save_params(
        &critic,
        &[(
            "",
            Critic::new(43, 6, &CriticConfig::paper(), 2)
                .unwrap()
                .params(),
        )],
    )
    .unwrap();
    check(&critic, &mut target, "MissingTensor");
    let mut nan = actor(1);
    nan.params_mut().tensor_mut("std.bias").unwrap()[2] = f32::NAN;
    let nan_path = dir.path().join("nan.safetensors");
    save_params(&nan_path, &[("", nan.params())]).unwrap();
    check(&nan_path, &mut target, "NonFinite");
    // A smaller actor's file does not fit the paper actor.
    let small = Actor::new(
        43,
        6,
        &ActorConfig {
            lstm_hidden: 50,
            ..ActorConfig::paper()
        },
        1,
    )
    .unwrap();
    let small_path = dir.path().join("small.safetensors");
    save_params(&small_path, &[("", small.params())]).unwrap();
    check(&small_path, &mut target, "ShapeMismatch");

    assert_eq!(
        target.params().to_flat(),
        before,
        "a failed load must not modify the parameters"
    );
}
