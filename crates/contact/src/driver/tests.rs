//! Tests of the contact loop (`driver`).
use super::*;
use crate::Change;
use crate::pairs::tests::stacked;

/// A level is split into the fewest equal steps of at most `max_step`: one level to λ = 1
/// in four, the sweep's fifths and a step of exactly `max_step` whole; a step that is not
/// positive and finite is refused by name, and so is a reserve's gap share that is negative or
/// not finite.
#[test]
fn long_levels_are_split_into_steps_of_at_most_max_step() {
    let (mesh, up, lo) = stacked();
    let faces = CrackFaces::from_sets(&mesh, &up, &lo).unwrap();
    let contact = Contact::with_faces(faces.clone(), ContactSettings::default()).unwrap();
    assert_eq!(contact.sublevels(0.0, 1.0), 4);
    assert_eq!(contact.sublevels(0.8, 1.0), 1);
    assert_eq!(contact.sublevels(0.0, 0.25), 1);
    assert_eq!(contact.sublevels(0.0, 0.26), 2);
    assert_eq!(contact.sublevels(1.0, 1.0), 1);
    // The step ends: `from` before the first, `to` itself after the last (not a sum that
    // could miss it by an ulp), equal steps between; the facade's steps without contact use
    // the same ends, so `auto` hands the loop a step the loop would have made.
    let ends: Vec<f64> = (0..=3)
        .map(|j| ContactSettings::sublevel_end(0.1, 0.9, j, 3))
        .collect();
    assert_eq!(ends[0], 0.1);
    assert_eq!(ends[3], 0.9);
    approx::assert_relative_eq!(ends[1], 0.1 + 0.8 / 3.0, max_relative = 1e-15);
    approx::assert_relative_eq!(ends[2], 0.1 + 1.6 / 3.0, max_relative = 1e-15);
    assert_eq!(contact.settings().sublevels(0.0, 1.0), 4);
    for bad in [0.0, -0.1, f64::NAN, f64::INFINITY] {
        let settings = ContactSettings {
            max_step: bad,
            ..ContactSettings::default()
        };
        let e = Contact::with_faces(faces.clone(), settings).unwrap_err();
        assert!(e.to_string().contains("max_step"), "{e}");
        let settings = ContactSettings {
            reserve: Reserve::Grow {
                rings: 2,
                gap_share: bad,
            },
            ..ContactSettings::default()
        };
        if bad != 0.0 {
            let e = Contact::with_faces(faces.clone(), settings).unwrap_err();
            assert!(e.to_string().contains("reserve.gap_share"), "{e}");
        }
    }
}

/// A set seen before at the level is a cycle: the error names the level and the pairs whose
/// state differs among the sets since its first visit (here pairs 1 and 2, which flip in
/// turn), not the pair that stayed; a new set passes until the pass limit.
#[test]
fn a_repeated_set_is_a_cycle_naming_the_flipping_pairs() {
    let (mesh, up, lo) = stacked();
    let faces = CrackFaces::from_sets(&mesh, &up, &lo).unwrap();
    let settings = ContactSettings {
        max_passes: 3,
        ..ContactSettings::default()
    };
    let contact = Contact::with_faces(faces, settings).unwrap();
    let change = Change::default();
    let seen = vec![
        vec![true, false, false, false],
        vec![true, true, false, false],
        vec![true, false, true, false],
    ];
    let e = contact
        .check_progress(0.75, &seen, &[true, true, false, false], 2, &change)
        .unwrap_err();
    match &e {
        ContactError::Cycle {
            lambda,
            passes,
            pairs,
        } => {
            assert_eq!((*lambda, *passes), (0.75, 2));
            let (a, b) = (contact.faces().pairs()[1], contact.faces().pairs()[2]);
            assert_eq!(pairs, &[a, b]);
        }
        other => panic!("{other}"),
    }
    assert_eq!(
        e.to_string(),
        "contact at λ = 0.75: the active set repeats after 2 passes (a cycle); the pairs \
         that flip: nodes 9/5, nodes 10/6"
    );
    assert!(
        contact
            .check_progress(0.75, &seen, &[false; 4], 2, &change)
            .is_ok()
    );
    assert!(matches!(
        contact.check_progress(0.75, &seen, &[false; 4], 3, &change),
        Err(ContactError::Passes { passes: 3, .. })
    ));
}

/// With `set_stable_only` a re-solve converged with negative pivots ends the level, naming the
/// load factor and the pivots; without it (the default) it does not, nor a stable state or
/// one whose inertia is unknown; the setter returns the previous setting.
#[test]
fn stable_only_refuses_a_converged_state_with_negative_pivots() {
    let (mesh, up, lo) = stacked();
    let faces = CrackFaces::from_sets(&mesh, &up, &lo).unwrap();
    let mut contact = Contact::with_faces(faces, ContactSettings::default()).unwrap();
    assert!(contact.check_stable(0.5, Some(2)).is_ok());
    assert!(!contact.set_stable_only(true));
    let e = contact.check_stable(0.5, Some(2)).unwrap_err();
    assert!(
        matches!(
            e,
            ContactError::Unstable {
                lambda: 0.5,
                pivots: 2
            }
        ),
        "{e}"
    );
    assert_eq!(
        e.to_string(),
        "contact at λ = 0.5: a pass converged on a state with 2 negative pivots where a stable \
         one was asked for"
    );
    assert!(contact.check_stable(0.5, Some(0)).is_ok());
    assert!(contact.check_stable(0.5, None).is_ok());
    assert!(contact.set_stable_only(false));
    assert!(contact.check_stable(0.5, Some(2)).is_ok());
}
