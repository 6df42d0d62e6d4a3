//! The paper's qualitative claims, on the default quadrotor and on the point mass: walls lower
//! the score, speed toward a wall lowers it, and it rises with distance from a wall.

mod common;

use common::{at, estimator, score};
use cstep::demo::scene::Scene;
use nalgebra::{UnitQuaternion, Vector3};

const MODELS: [&str; 2] = ["model:=quadrotor", "model:=point_mass"];

#[test]
fn open_space_scores_above_a_wide_corridor_above_a_narrow_one() {
    for model in MODELS {
        let e = estimator(&[model]);
        let open = score(&e, &Scene::open(), &at(0.0, 0.0));
        let wide = score(&e, &Scene::corridor(2.5, 20.0), &at(0.0, 0.0));
        let narrow = score(&e, &Scene::corridor(1.0, 20.0), &at(0.0, 0.0));
        assert!(open.valid() && wide.valid() && narrow.valid(), "{model}");
        assert!(
            open.empowerment > wide.empowerment + 0.1
                && wide.empowerment > narrow.empowerment + 0.1,
            "{model}: open {:.3}, wide {:.3}, narrow {:.3}",
            open.empowerment,
            wide.empowerment,
            narrow.empowerment
        );
    }
}

#[test]
fn speed_toward_a_wall_scores_below_speed_away_from_it() {
    let wall = Scene::open().wall(1.0, -20.0, 1.0, 20.0);
    for model in MODELS {
        let e = estimator(&[model]);
        let toward = score(
            &e,
            &wall,
            &at(0.0, 0.0).with_velocity(Vector3::new(1.5, 0.0, 0.0)),
        );
        let still = score(&e, &wall, &at(0.0, 0.0));
        let away = score(
            &e,
            &wall,
            &at(0.0, 0.0).with_velocity(Vector3::new(-1.5, 0.0, 0.0)),
        );
        assert!(
            toward.empowerment < still.empowerment && still.empowerment < away.empowerment,
            "{model}: toward {:.3}, still {:.3}, away {:.3}",
            toward.empowerment,
            still.empowerment,
            away.empowerment
        );
    }
}

#[test]
fn the_score_rises_as_the_robot_moves_away_from_a_wall() {
    let wall = Scene::open().wall(0.0, -20.0, 0.0, 20.0);
    for model in MODELS {
        let e = estimator(&[model]);
        let scores: Vec<f64> = [0.2, 0.4, 0.7, 1.0, 1.5, 2.0]
            .iter()
            .map(|&d| score(&e, &wall, &at(-d, 0.0)).empowerment)
            .collect();
        assert!(
            scores.windows(2).all(|w| w[1] > w[0]),
            "{model}: {scores:.3?} should increase with distance"
        );
    }
}

#[test]
fn a_quadrotor_tilted_toward_a_wall_scores_below_one_tilted_away() {
    // Physics-informed: the same position and velocity, but an attitude that is already
    // accelerating toward the wall leaves less room to stop.
    let wall = Scene::open().wall(0.8, -20.0, 0.8, 20.0);
    let e = estimator(&["model:=quadrotor"]);
    let pitch = 0.5; // rad; positive pitch tilts thrust toward +x
    let toward = at(0.0, 0.0).with_attitude(UnitQuaternion::from_euler_angles(0.0, pitch, 0.0));
    let away = at(0.0, 0.0).with_attitude(UnitQuaternion::from_euler_angles(0.0, -pitch, 0.0));
    let (toward, away) = (score(&e, &wall, &toward), score(&e, &wall, &away));
    assert!(
        toward.empowerment < away.empowerment,
        "toward {:.3}, away {:.3}",
        toward.empowerment,
        away.empowerment
    );
}

#[test]
fn three_dimensional_volumes_follow_the_same_order_and_respect_floor_and_ceiling() {
    let e = estimator(&["volume_dims:=3", "floor_height:=0.0", "ceiling_height:=2.0"]);
    let open = score(&e, &Scene::open(), &at(0.0, 0.0));
    let narrow = score(&e, &Scene::corridor(1.0, 20.0), &at(0.0, 0.0));
    assert!(open.valid() && narrow.valid());
    assert!(open.empowerment > narrow.empowerment + 0.1);
    let low = score(
        &e,
        &Scene::open(),
        &cstep::state::RobotState::at_rest(Vector3::new(0.0, 0.0, 0.3)),
    );
    assert!(
        low.empowerment < open.empowerment,
        "near the floor {:.3} vs mid-height {:.3}",
        low.empowerment,
        open.empowerment
    );
    for endpoint in open
        .rollout
        .endpoints
        .iter()
        .zip(&open.rollout.terminal)
        .filter(|(_, t)| !**t)
    {
        let z = 1.0 + endpoint.0[2];
        assert!((0.0..=2.0).contains(&z), "a free endpoint at z = {z}");
    }
}

#[test]
fn a_seed_fixes_the_score_bit_for_bit_and_another_seed_changes_it() {
    let scene = Scene::corridor(2.0, 20.0);
    let state = at(0.0, 0.3).with_velocity(Vector3::new(0.7, 0.2, 0.0));
    for model in MODELS {
        let a = score(&estimator(&[model, "seed:=11"]), &scene, &state);
        let b = score(&estimator(&[model, "seed:=11"]), &scene, &state);
        let c = score(&estimator(&[model, "seed:=12"]), &scene, &state);
        assert_eq!(a.empowerment.to_bits(), b.empowerment.to_bits(), "{model}");
        assert_eq!(a.rollout, b.rollout, "{model}");
        assert_ne!(a.empowerment, c.empowerment, "{model}");
    }
}

#[test]
fn collisions_at_start_and_no_way_out_give_the_floor_and_valid_false() {
    let e = estimator(&[]);
    let touching = score(
        &e,
        &Scene::open().wall(0.03, -5.0, 0.03, 5.0),
        &at(0.0, 0.0),
    );
    assert!(!touching.valid());
    assert_eq!(touching.status.as_str(), "robot already in collision");
    assert_eq!(touching.empowerment, cstep::estimator::EMPOWERMENT_FLOOR);
    let boxed = score(
        &e,
        &Scene::open().boxed(-0.08, -0.08, 0.08, 0.08),
        &at(0.0, 0.0),
    );
    assert!(!boxed.valid());
    assert_eq!(boxed.status.as_str(), "every sampled trajectory collides");
    assert_eq!(boxed.empowerment, cstep::estimator::EMPOWERMENT_FLOOR);
    assert_eq!(boxed.volumes.free, 0.0);
}
