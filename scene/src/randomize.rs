//! Random layouts of a task: furniture, rigid groups and objects moved within their ranges,
//! redrawn until the task can be done in the layout.

use crate::error::SceneError;
use crate::layout::{check_layout, Infeasible};
use crate::motion::Motion;
use crate::task::Task;
use crate::world::World;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Layouts drawn from one seed before giving up. The built-in tasks accept well over a third
/// of their draws (see `tasks/README.md`), so this is only reached when the ranges and rules
/// leave (almost) no feasible layout.
pub(crate) const MAX_DRAWS: usize = 1000;

/// A random layout of `task`, as [`randomize_layout_with`] returns it.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    /// The task's world with everything moved.
    pub world: World,
    /// Why each earlier draw from the same seed was rejected, in draw order.
    pub(crate) rejected: Vec<Infeasible>,
}

/// The task's world with its furniture, groups and objects moved at random within their
/// ranges (see [`Motion::draw`]), in a layout the task can be done in (its layout rules).
///
/// Deterministic per seed (ChaCha8): a rejected draw is followed by the next draw from the
/// same generator, so the layout of a seed never depends on other seeds or on threads.
pub fn randomize(task: &Task, seed: u64) -> Result<World, SceneError> {
    randomize_layout(task, seed).map(|l| l.world)
}

/// [`randomize`], also returning why the draws before the accepted one were rejected.
pub(crate) fn randomize_layout(task: &Task, seed: u64) -> Result<Layout, SceneError> {
    randomize_layout_with(task, seed, &|_| Ok(()))
}

/// [`randomize`] with a further test every layout must pass, or be redrawn like an
/// infeasible one: `accept` says why a layout is refused. The execution engine passes its
/// check that the layout stands still when simulated untouched, which this crate, knowing no
/// physics, cannot make.
pub fn randomize_layout_with(
    task: &Task,
    seed: u64,
    accept: &dyn Fn(&World) -> Result<(), String>,
) -> Result<Layout, SceneError> {
    let motion = Motion::of(task)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut rejected = Vec::new();
    for _ in 0..MAX_DRAWS {
        let world = motion.draw(&task.world, &mut rng);
        match check_layout(task, &world)
            .and_then(|()| accept(&world).map_err(Infeasible::Unsettled))
        {
            Ok(()) => return Ok(Layout { world, rejected }),
            Err(why) => rejected.push(why),
        }
    }
    Err(SceneError::Randomize {
        seed,
        draws: MAX_DRAWS,
        last: rejected.last().map(|w| w.to_string()).unwrap_or_default(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtin;
    use crate::layout::Infeasible;
    use crate::Range;
    use akl_tsr::nalgebra::Vector3;

    #[test]
    fn the_same_seed_gives_the_same_world() {
        for name in builtin::names() {
            let t = builtin::task(name).unwrap().unwrap();
            assert_eq!(randomize(&t, 7).unwrap(), randomize(&t, 7).unwrap());
            assert_ne!(randomize(&t, 7).unwrap(), randomize(&t, 8).unwrap());
        }
    }

    /// A rejected draw is redrawn from the same seed's generator: replaying that generator
    /// gives the rejected draws for the reasons reported, then the layout; nothing else (other
    /// seeds, threads) enters.
    #[test]
    fn redraws_come_from_the_seeds_own_generator() {
        let t = builtin::task("pick_place").unwrap().unwrap();
        let motion = Motion::of(&t).unwrap();
        let mut redrawn = 0;
        for seed in 0..100 {
            let layout = randomize_layout(&t, seed).unwrap();
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            for why in &layout.rejected {
                let draw = motion.draw(&t.world, &mut rng);
                assert_eq!(check_layout(&t, &draw).as_ref(), Err(why), "seed {seed}");
            }
            assert_eq!(motion.draw(&t.world, &mut rng), layout.world, "seed {seed}");
            redrawn += usize::from(!layout.rejected.is_empty());
        }
        assert!(
            redrawn > 10,
            "pick_place redraws some layouts ({redrawn} of 100)"
        );
    }

    /// A layout the further test refuses is redrawn like an infeasible one, from the same
    /// generator, and why is kept.
    #[test]
    fn a_layout_the_further_test_refuses_is_redrawn() {
        let t = builtin::task("pick_place").unwrap().unwrap();
        let nominal = t.world.object("block_a").unwrap().pose.translation.x;
        let refuse_right = |w: &World| {
            let x = w.object("block_a").unwrap().pose.translation.x;
            if x > nominal {
                Err(format!("block_a {:.1} mm right", (x - nominal) * 1e3))
            } else {
                Ok(())
            }
        };
        let mut refused = 0;
        for seed in 0..20 {
            let layout = randomize_layout_with(&t, seed, &refuse_right).unwrap();
            assert!(layout.world.object("block_a").unwrap().pose.translation.x <= nominal);
            refused += layout
                .rejected
                .iter()
                .filter(|r| matches!(r, Infeasible::Unsettled(why) if why.contains("right")))
                .count();
            assert_eq!(
                randomize_layout_with(&t, seed, &refuse_right).unwrap(),
                layout,
                "seed {seed}"
            );
        }
        assert!(refused > 5, "{refused}");
    }

    /// The radius of the largest ball about the shape's origin inside it (none for a mesh).
    fn inscribed(shape: &crate::Shape) -> f64 {
        match shape {
            crate::Shape::Mesh { .. } => 0.0,
            _ => shape.half_extents().min(),
        }
    }

    /// Checked with measures of their own, not with `check_layout`, which chose the layouts:
    /// movable objects' centres at least `min_gap` plus their inscribed balls apart (a gap of
    /// `min_gap` implies it), every object's centre over its nominal support's bounding box,
    /// every teaching target within reach, rigid groups rigid, heights and uprightness kept.
    #[test]
    fn layouts_keep_groups_rigid_gaps_supports_and_reach() {
        for name in builtin::names() {
            let t = builtin::task(name).unwrap().unwrap();
            let relations = t.fixed_relations().unwrap();
            let mut nearest_gap = f64::INFINITY;
            for seed in 0..300 {
                let w = randomize(&t, seed).unwrap();
                let movable: Vec<_> = w.objects.iter().filter(|o| o.movable).collect();
                for (i, a) in movable.iter().enumerate() {
                    for b in &movable[i + 1..] {
                        let apart = (a.pose.translation.vector - b.pose.translation.vector).norm()
                            - inscribed(&a.shape)
                            - inscribed(&b.shape);
                        nearest_gap = nearest_gap.min(apart);
                        assert!(
                            apart >= t.min_gap - 1e-9,
                            "{name} seed {seed}: {} and {} {apart} m apart",
                            a.name,
                            b.name
                        );
                    }
                }
                for o in &w.objects {
                    let Some(support) = t.world.support_of(&o.name) else {
                        continue;
                    };
                    let under = w.object(&support.name).unwrap();
                    let local = (under.pose.inverse() * o.pose).translation.vector;
                    let half = under.shape.half_extents();
                    assert!(
                        local.x.abs() <= half.x + 1e-9 && local.y.abs() <= half.y + 1e-9,
                        "{name} seed {seed}: {} is not over {}",
                        o.name,
                        support.name
                    );
                }
                let shoulder = Vector3::from(t.reach.shoulder);
                for target in t.teaching.targets(&w).unwrap() {
                    let p = (w.robot_base.inverse() * target).translation.vector;
                    assert!((p - shoulder).norm() <= t.reach.max, "{name} seed {seed}");
                }
                for set in &relations {
                    let pose = |n: &str| {
                        w.object(n).map_or(akl_tsr::Pose::identity(), |o| o.pose)
                            * t.world
                                .object(n)
                                .map_or(akl_tsr::Pose::identity(), |o| o.pose)
                                .inverse()
                    };
                    let first = pose(&set.members[0]);
                    for m in &set.members[1..] {
                        let d = first.inverse() * pose(m);
                        assert!(
                            d.translation.vector.norm() < 1e-9 && d.rotation.angle() < 1e-9,
                            "{name} seed {seed}: {m} moved against {}",
                            set.members[0]
                        );
                    }
                }
                for o in &w.objects {
                    let before = t.world.object(&o.name).unwrap();
                    assert!((o.pose.translation.z - before.pose.translation.z).abs() < 1e-12);
                    let up = o.pose.rotation * (before.pose.rotation.inverse() * Vector3::z());
                    assert!((up.z - 1.0).abs() < 1e-12, "{name}: {} tilted", o.name);
                }
            }
            assert!(
                nearest_gap.is_finite() || t.world.objects.iter().filter(|o| o.movable).count() < 2
            );
        }
    }

    #[test]
    fn every_range_is_used_within_its_bounds() {
        for name in builtin::names() {
            let t = builtin::task(name).unwrap().unwrap();
            let motion = Motion::of(&t).unwrap();
            for m in motion.movers.iter().filter(|m| m.range.is_some()) {
                let r = m.range.unwrap();
                let member = &m.members[0];
                let carrier = m.carrier.map(|c| motion.movers[c].members[0].clone());
                let relative = |w: &World| {
                    let base = carrier
                        .as_ref()
                        .map_or(akl_tsr::Pose::identity(), |c| w.object(c).unwrap().pose);
                    base.inverse() * w.object(member).unwrap().pose
                };
                let nominal = relative(&t.world);
                let mut extremes = [f64::INFINITY, f64::NEG_INFINITY];
                for seed in 0..300 {
                    let now = relative(&randomize(&t, seed).unwrap());
                    let yaw = (nominal.rotation.inverse() * now.rotation).euler_angles().2;
                    assert!(
                        yaw >= r.yaw[0] - 1e-9 && yaw <= r.yaw[1] + 1e-9,
                        "{name}: {} turned {yaw}",
                        m.name
                    );
                    extremes = [extremes[0].min(yaw), extremes[1].max(yaw)];
                }
                if r.yaw[1] > r.yaw[0] {
                    let span = r.yaw[1] - r.yaw[0];
                    assert!(
                        extremes[1] - extremes[0] > 0.5 * span,
                        "{name}: {} turns over {extremes:?} of {:?}",
                        m.name,
                        r.yaw
                    );
                }
            }
        }
    }

    #[test]
    fn no_feasible_layout_fails_with_the_seed_and_the_last_reason() {
        let mut t = builtin::task("pick_place").unwrap().unwrap();
        // Force block_a onto block_b's spot and forbid any other place.
        let b = t.world.object("block_b").unwrap().pose.translation.vector;
        let a = t.world.object("block_a").unwrap().pose.translation.vector;
        t.randomize.insert(
            "block_a".into(),
            Range {
                x: [b.x - a.x; 2],
                y: [b.y - a.y; 2],
                yaw: [0.0; 2],
            },
        );
        t.randomize.remove("shelf_1");
        let e = randomize(&t, 1).unwrap_err().to_string();
        assert!(e.contains("seed 1") && e.contains("block_a"), "{e}");
    }

    /// The share of draws the built-in tasks accept (printed with `--nocapture`; quoted in
    /// tasks/README.md).
    #[test]
    fn the_built_in_tasks_accept_most_draws() {
        for name in builtin::names() {
            let t = builtin::task(name).unwrap().unwrap();
            let rejected: usize = (0..500)
                .map(|s| randomize_layout(&t, s).unwrap().rejected.len())
                .sum();
            let accepted = 500.0 / (500 + rejected) as f64;
            println!("{name}: {:.1} % of draws accepted", 100.0 * accepted);
            assert!(accepted > 1.0 / 3.0, "{name}: {accepted}");
        }
    }

    #[test]
    fn rejections_say_why() {
        let t = builtin::task("pick_place").unwrap().unwrap();
        let reasons: Vec<Infeasible> = (0..100)
            .flat_map(|s| randomize_layout(&t, s).unwrap().rejected)
            .collect();
        assert!(reasons
            .iter()
            .any(|r| matches!(r, Infeasible::TooClose { .. })));
    }
}
