//! Contract: the flat parameter vector (the ES genome) round-trips through get/set, covers
//! every named tensor exactly once in order, rejects wrong lengths, and drives the network;
//! Polyak averaging and hard copies act elementwise on it.

use esrl_nn::*;

#[test]
fn get_set_round_trip_and_layout() {
    let mut a = Actor::new(43, 6, &ActorConfig::paper(), 1).unwrap();
    let flat = a.params().to_flat();
    assert_eq!(flat.len(), a.num_params());
    // Specs tile the vector exactly, in order.
    let mut next = 0;
    for s in a.params().specs() {
        assert_eq!(s.offset, next, "{}", s.name);
        next += s.len();
    }
    assert_eq!(next, flat.len());

    let perturbed: Vec<f32> = flat
        .iter()
        .enumerate()
        .map(|(i, v)| v + 0.25 * ((i as f32) * 0.7).sin())
        .collect();
    a.params_mut().set_flat(&perturbed).unwrap();
    assert_eq!(a.params().to_flat(), perturbed);
    assert_eq!(a.params().tensor("fc.0.weight").unwrap()[0], perturbed[0]);
    a.params_mut().set_flat(&flat).unwrap();
    assert_eq!(a.params().as_slice(), flat.as_slice());

    let err = a.params_mut().set_flat(&flat[1..]).unwrap_err();
    assert!(
        matches!(err, NnError::LengthMismatch { expected, found, .. } if expected == flat.len() && found == flat.len() - 1)
    );
}

#[test]
fn flat_vector_drives_the_outputs() {
    let a = Actor::new(
        5,
        2,
        &ActorConfig {
            fc: vec![8],
            lstm_hidden: 4,
            ..ActorConfig::default()
        },
        1,
    )
    .unwrap();
    let mut b = Actor::new(
        5,
        2,
        &ActorConfig {
            fc: vec![8],
            lstm_hidden: 4,
            ..ActorConfig::default()
        },
        2,
    )
    .unwrap();
    let run = |x: &Actor| {
        let mut st = x.step_state();
        x.step(&[0.1, -0.2, 0.3, 0.4, -0.5], &mut st);
        st.mean().to_vec()
    };
    assert_ne!(run(&a), run(&b));
    b.params_mut().set_flat(a.params().as_slice()).unwrap();
    assert_eq!(run(&a), run(&b));
}

#[test]
fn polyak_and_copy() {
    let src = Critic::new(4, 2, &CriticConfig::feed_forward(), 1).unwrap();
    let mut dst = Critic::new(4, 2, &CriticConfig::feed_forward(), 2).unwrap();
    let (s, d0) = (src.params().to_flat(), dst.params().to_flat());
    dst.params_mut().polyak_update(src.params(), 0.1).unwrap();
    for ((n, o), s) in dst.params().as_slice().iter().zip(&d0).zip(&s) {
        assert!((n - (0.1 * s + 0.9 * o)).abs() < 1e-6);
    }
    dst.params_mut().copy_from(src.params()).unwrap();
    assert_eq!(dst.params().as_slice(), src.params().as_slice());
    let other = Actor::new(4, 2, &ActorConfig::feed_forward(), 1).unwrap();
    assert!(dst.params_mut().polyak_update(other.params(), 0.1).is_err());
    // A clone is a distinct parameter set for gradients.
    assert_ne!(src.params().id(), src.clone().params().id());
}
