//! What the randomization ranges of the built-in tasks do to a keyframe grounded on the wrong
//! object: it must land elsewhere in nearly every layout, and where the task's goals depend on
//! it (the inspection's scan line, the assembly's slide into the clamp) the goals must fail.
//!
//! A keyframe is re-grounded as a spec author might get it wrong: on another object (or the
//! world), its offset recomputed so that its pose in the task file's own layout is unchanged.
//! Poses are read in the layout as drawn, before anything is moved by the robot.

use akl_scene::{builtin, randomize, Goal, ObjectPaths, Task, World};
use akl_tsr::{Keyframe, Pose, Tsr, WORLD_FRAME};

/// Layouts drawn per task.
const LAYOUTS: u64 = 200;

fn pose_of(world: &World, name: &str) -> Pose {
    if name == WORLD_FRAME {
        Pose::identity()
    } else {
        world.object(name).unwrap().pose
    }
}

fn layouts(t: &Task) -> Vec<World> {
    (0..LAYOUTS).map(|s| randomize(t, s).unwrap()).collect()
}

/// Where keyframe `kf`'s nominal pose lands in `world` when grounded on `on` instead of its
/// reference (offset kept so that the task file's layout gives the same pose).
fn regrounded(t: &Task, kf: &Keyframe, on: &str, world: &World) -> Pose {
    let nominal = pose_of(&t.world, &kf.reference) * kf.tsr.tw_e;
    pose_of(world, on) * (pose_of(&t.world, on).inverse() * nominal)
}

/// Every name a keyframe could be grounded on: the objects and the world.
fn references(t: &Task) -> Vec<String> {
    t.world
        .names()
        .map(String::from)
        .chain([WORLD_FRAME.to_string()])
        .collect()
}

fn goal<'t>(t: &'t Task, kind: &str) -> &'t Goal {
    t.goals.iter().find(|g| g.kind() == kind).unwrap()
}

/// The share of layouts in which `fails` says the wrongly grounded keyframe shows.
fn share(worlds: &[World], fails: impl Fn(&World) -> bool) -> f64 {
    worlds.iter().filter(|w| fails(w)).count() as f64 / worlds.len() as f64
}

#[test]
fn a_keyframe_grounded_on_an_object_the_layouts_move_apart_lands_outside_its_tsr() {
    for name in builtin::names() {
        let t = builtin::task(name).unwrap().unwrap();
        let worlds = layouts(&t);
        for (k, kf) in t.truth.as_ref().unwrap().keyframes.iter().enumerate() {
            for other in references(&t) {
                if t.held_together(&kf.reference, &other).unwrap() {
                    continue;
                }
                let missed = share(&worlds, |w| {
                    let right = Tsr::new(pose_of(w, &kf.reference), kf.tsr.tw_e, kf.tsr.bw);
                    !right.contains(&regrounded(&t, kf, &other, w))
                });
                // The pipe only slides along the rail (±2 cm): grounded on the clamp group
                // instead, a pipe keyframe is off by about 1 cm, outside its ±5 mm TSR in
                // about 70 % of layouts. Everything else moves by a few centimetres.
                let pair = [kf.reference.as_str(), other.as_str()];
                let slide_only = name == "assembly"
                    && pair.contains(&"pipe")
                    && pair
                        .iter()
                        .any(|n| *n != "pipe" && t.held_together(n, "rail").unwrap());
                let least = if slide_only { 0.6 } else { 0.95 };
                println!(
                    "{name} keyframe {k} on {other} instead of {}: outside its TSR in {missed:.3}",
                    kf.reference
                );
                assert!(
                    missed >= least,
                    "{name} keyframe {k} on {other} instead of {}: outside the TSR in only {missed:.3} of layouts",
                    kf.reference
                );
            }
        }
    }
}

#[test]
fn equivalent_groundings_land_on_the_same_pose_in_every_layout() {
    for name in builtin::names() {
        let t = builtin::task(name).unwrap().unwrap();
        let worlds = layouts(&t);
        for kf in &t.truth.as_ref().unwrap().keyframes {
            for other in references(&t) {
                if !t.held_together(&kf.reference, &other).unwrap() {
                    continue;
                }
                for w in &worlds {
                    let right = pose_of(w, &kf.reference) * kf.tsr.tw_e;
                    let d = right.inverse() * regrounded(&t, kf, &other, w);
                    assert!(
                        d.translation.vector.norm() < 1e-9 && d.rotation.angle() < 1e-9,
                        "{name}: {other} is listed as held together with {}",
                        kf.reference
                    );
                }
            }
        }
    }
}

#[test]
fn the_scan_line_must_be_grounded_on_the_scanner_row() {
    let t = builtin::task("inspection").unwrap().unwrap();
    let truth = t.truth.as_ref().unwrap();
    let grasp = truth.keyframes[0].tsr.tw_e;
    let scan = goal(&t, "scan");
    let worlds = layouts(&t);
    // The part's path when the line between keyframes 1 and 2 is grounded on `on`.
    let fails = |on: &str, w: &World| {
        let ends: Vec<Pose> = truth.keyframes[1..3]
            .iter()
            .map(|kf| regrounded(&t, kf, on, w))
            .collect();
        let mut paths = ObjectPaths::new();
        for k in 0..=100 {
            let tcp = ends[0].lerp_slerp(&ends[1], f64::from(k) / 100.0);
            paths.push("part", f64::from(k) * 0.01, tcp * grasp.inverse());
        }
        !scan.check(w, &paths, &t.world).holds
    };
    for scanner in ["scanner_1", "scanner_2", "scanner_3"] {
        assert_eq!(share(&worlds, |w| fails(scanner, w)), 0.0, "{scanner}");
    }
    for other in ["world", "table", "shelf_1", "shelf_2", "part"] {
        let failed = share(&worlds, |w| fails(other, w));
        println!("scan line on {other}: the goal fails in {failed:.3} of layouts");
        assert!(
            failed >= 0.9,
            "scan line on {other}: fails in only {failed:.3}"
        );
    }
}

#[test]
fn the_slide_into_the_clamp_must_be_grounded_on_the_clamp() {
    let t = builtin::task("assembly").unwrap().unwrap();
    let truth = t.truth.as_ref().unwrap();
    let grasp = truth.keyframes[2].tsr.tw_e;
    let release = &truth.keyframes[3];
    let inside = goal(&t, "inside");
    let worlds = layouts(&t);
    // The pipe where the hand leaves it when the line's end is grounded on `on`.
    let fails = |on: &str, w: &World| {
        let mut end = w.clone();
        end.object_mut("pipe").unwrap().pose = regrounded(&t, release, on, w) * grasp.inverse();
        !inside.check(&end, &ObjectPaths::new(), &t.world).holds
    };
    for member in ["rail", "clamp_left", "clamp_right", "clamp_top"] {
        assert_eq!(share(&worlds, |w| fails(member, w)), 0.0, "{member}");
    }
    for other in ["world", "table", "shelf_1", "shelf_2", "block"] {
        let failed = share(&worlds, |w| fails(other, w));
        println!("clamp line on {other}: the goal fails in {failed:.3} of layouts");
        assert!(
            failed >= 0.9,
            "clamp line on {other}: fails in only {failed:.3}"
        );
    }
}
