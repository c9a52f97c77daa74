//! Contract: identical content gives byte-identical safetensors files, whatever order the
//! metadata map iterates in (so checkpoints of identical weights have identical hashes).

use esrl_nn::{load_tensors, save_tensors, NamedTensor};
use std::collections::HashMap;

#[test]
fn identical_tensors_and_metadata_give_identical_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let tensors = vec![
        NamedTensor {
            name: "b".into(),
            shape: vec![2],
            data: vec![1.0, 2.0],
        },
        NamedTensor {
            name: "a".into(),
            shape: vec![1, 3],
            data: vec![3.0, 4.0, 5.0],
        },
    ];
    let mut files = Vec::new();
    for k in 0..6 {
        // A fresh map each time: each HashMap gets its own random iteration order.
        let meta: HashMap<String, String> = (0..12)
            .map(|i| (format!("key{i}"), format!("value {i}")))
            .collect();
        let path = dir.path().join(format!("t{k}.safetensors"));
        save_tensors(&path, &tensors, Some(meta)).unwrap();
        files.push(std::fs::read(&path).unwrap());
    }
    for f in &files[1..] {
        assert_eq!(f, &files[0], "same content, same bytes");
    }
    let back = load_tensors(&dir.path().join("t0.safetensors")).unwrap();
    assert_eq!(back["a"].data, vec![3.0, 4.0, 5.0]);
    assert_eq!(back["b"].shape, vec![2]);
}
