//! Tests of the collision checks.

use super::cull::placed;
use super::{Checker, Held, Hit, Margins, RobotCollision, Scene};
use crate::contact_rules::Allowances;
use crate::parry_convert;
use crate::robot::Robot;
use akl_scene::World;
use akl_tsr::Pose;

/// The pick-and-place world with a fixed box `name` of `size` centred at `at`.
fn pick_place_with_box(name: &str, size: [f64; 3], at: [f64; 3]) -> World {
    let mut world = akl_scene::builtin::task("pick_place")
        .unwrap()
        .unwrap()
        .world;
    world.objects.push(akl_scene::Object {
        name: name.into(),
        shape: akl_scene::Shape::Box { size },
        pose: akl_tsr::pose::pose_from_xyz(at),
        movable: false,
        mass: 0.0,
        friction: 0.5,
    });
    world
}

/// The pick-and-place world with a plate under the fingers at `q`, raised (to a micrometre)
/// until `q`'s plain check just meets it: the hand keeps more than half its margin from the
/// plate, but not all of it.
pub(crate) fn plate_just_within_the_margin(
    robot: &Robot,
    model: &RobotCollision,
    q: &[f64],
) -> World {
    let tcp = robot.tcp_pose(q).translation.vector;
    let plate = |z: f64| pick_place_with_box("plate", [0.3, 0.3, 0.01], [tcp.x, tcp.y, z]);
    let meets = |z: f64| {
        let scene = Scene::new(&plate(z), &[]);
        Checker::new(robot, model, &scene)
            .check(q, 0.08, None, &Allowances::default())
            .is_some()
    };
    let (mut free, mut hit) = (tcp.z - 0.2, tcp.z);
    assert!(!meets(free) && meets(hit));
    while hit - free > 1e-6 {
        let z = 0.5 * (free + hit);
        if meets(z) {
            hit = z;
        } else {
            free = z;
        }
    }
    plate(hit)
}

mod checks {
    use super::*;
    use akl_scene::builtin;
    use akl_tsr::pose::pose_from_xyz_rpy;
    use proptest::prelude::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::f64::consts::PI;

    fn none() -> Allowances {
        Allowances::default()
    }

    #[test]
    fn the_ready_pose_is_free_in_every_task_and_the_table_is_the_mount() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        for name in builtin::names() {
            let task = builtin::task(name).unwrap().unwrap();
            let scene = Scene::new(&task.world, &[]);
            assert_eq!(scene.mount(), Some("table"));
            let checker = Checker::new(&robot, &model, &scene);
            assert_eq!(
                checker.check(robot.ready(), 0.08, None, &none()),
                None,
                "{name}"
            );
        }
    }

    #[test]
    fn the_hand_in_the_table_is_a_collision_named_by_link_and_object() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let task = builtin::task("pick_place").unwrap().unwrap();
        let scene = Scene::new(&task.world, &[]);
        let checker = Checker::new(&robot, &model, &scene);
        let low = pose_from_xyz_rpy([0.65, 0.0, 0.01], [PI, 0.0, 0.0]);
        let q = robot.ik(&low, robot.ready()).unwrap();
        match checker.check(&q, 0.08, None, &none()) {
            Some(Hit::World(link, object)) => {
                assert!(link.contains("finger") || link.contains("hand"), "{link}");
                assert_eq!(object, "table");
            }
            other => panic!("expected the hand on the table, got {other:?}"),
        }
        assert_eq!(
            checker.check(
                &q,
                0.08,
                None,
                &Allowances {
                    hand_may_touch: vec!["table".into()],
                    ..Allowances::default()
                }
            ),
            None
        );
    }

    #[test]
    fn self_collisions_name_two_links_that_may_not_touch() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let scene = Scene::new(
            &World {
                robot_base: Pose::identity(),
                objects: vec![],
            },
            &[],
        );
        let checker = Checker::new(&robot, &model, &scene);
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut found = 0;
        for _ in 0..500 {
            let q: Vec<f64> = robot
                .joint_limits()
                .iter()
                .map(|[lo, hi]| rng.gen_range(*lo..*hi))
                .collect();
            if let Some(Hit::SelfCollision(a, b)) = checker.check(&q, 0.08, None, &none()) {
                found += 1;
                let allowed = robot
                    .config()
                    .collision
                    .allowed_pairs
                    .iter()
                    .any(|[x, y]| (x == &a && y == &b) || (x == &b && y == &a));
                assert!(!allowed && a != b, "{a} with {b}");
            }
        }
        assert!(found > 0);
        let out = [0.0, 0.0, 0.0, 0.5, 0.0, 1.0, 0.0];
        assert_eq!(checker.check(&out, 0.08, None, &none()), Some(Hit::Limits));
    }

    /// A held object keeps the hand margin from the arm's own links (its place in the hand is
    /// only as good as the perception the grasp was planned on), not the smaller held margin
    /// it keeps from the world: moved up from the elbow, a held ball must stand about the
    /// difference (3 mm for the Panda) further off before the check calls it free.
    #[test]
    fn a_held_object_keeps_the_hand_margin_from_the_arm() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let world = World {
            robot_base: Pose::identity(),
            objects: Vec::new(),
        };
        let scene = Scene::new(&world, &[]);
        let checker = Checker::new(&robot, &model, &scene);
        let q = robot.ready();
        let elbow = robot
            .links()
            .iter()
            .position(|l| l.name == "fer_link4")
            .unwrap();
        let from = robot.link_poses(q, 0.08)[elbow].translation.vector;
        let tcp = robot.tcp_pose(q);
        let margins = model.margins();
        assert!(margins.hand > margins.held + 0.002);
        let held_margin_only = Margins {
            hand: margins.held,
            ..margins
        };
        // The least rise (0.1 mm steps) at which a 1 cm ball is free with `m`.
        let free_from = |m: &Margins| {
            (0..3000)
                .map(|k| k as f64 * 1e-4)
                .find(|&t| {
                    let centre = Pose::from_parts(
                        (from + akl_tsr::nalgebra::Vector3::z() * t).into(),
                        Default::default(),
                    );
                    let ball = akl_scene::Shape::Sphere { radius: 0.01 };
                    let held = Held::new("ball", ball, tcp.inverse() * centre, m);
                    checker.check(q, 0.08, Some(&held), &none()).is_none()
                })
                .unwrap()
        };
        let (near, far) = (free_from(&held_margin_only), free_from(&margins));
        assert!(
            far - near > 0.8 * (margins.hand - margins.held),
            "free from {near:.4} m with the held margin, {far:.4} m with the hand's"
        );
    }

    /// A held object keeps the hand margin from a movable object (perceived, as the object in
    /// the hand was), the held margin from a fixed one: a held ball 3.5 mm from a small box is
    /// free beside furniture and refused beside a movable box (Panda: held 2 mm, hand 5 mm).
    #[test]
    fn a_held_object_keeps_the_hand_margin_from_movable_objects() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let margins = model.margins();
        let gap = 0.5 * (margins.held + margins.hand);
        assert!(margins.hand > gap && gap > margins.held);
        let q = robot.ready();
        let tcp = robot.tcp_pose(q);
        // A 1 cm ball 8 cm beyond the TCP along its approach axis, clear of the fingers.
        let centre = tcp * Pose::from_parts([0.0, 0.0, 0.08].into(), Default::default());
        let ball = akl_scene::Shape::Sphere { radius: 0.01 };
        let held = Held::new("ball", ball, tcp.inverse() * centre, &margins);
        let side = tcp.rotation * akl_tsr::nalgebra::Vector3::x();
        let half = 0.005;
        let box_at = centre.translation.vector + side * (0.01 + gap + half);
        let checked = |movable: bool| {
            let world = World {
                robot_base: Pose::identity(),
                objects: vec![akl_scene::Object {
                    name: "box".into(),
                    shape: akl_scene::Shape::Box {
                        size: [2.0 * half; 3],
                    },
                    pose: Pose::from_parts(box_at.into(), tcp.rotation),
                    movable,
                    mass: 0.1,
                    friction: 0.5,
                }],
            };
            let scene = Scene::new(&world, &[]);
            let checker = Checker::new(&robot, &model, &scene);
            assert!(
                checker.check(q, 0.08, None, &none()).is_none(),
                "the hand is clear"
            );
            checker.check(q, 0.08, Some(&held), &none())
        };
        assert_eq!(checked(false), None);
        assert_eq!(
            checked(true),
            Some(Hit::HeldWorld("ball".into(), "box".into()))
        );
    }

    #[test]
    fn a_held_block_collides_with_its_support_unless_allowed() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let task = builtin::task("pick_place").unwrap().unwrap();
        let block = task.world.object("block_a").unwrap();
        let grasp = block.pose * pose_from_xyz_rpy([0.0, 0.0, 0.015], [PI, 0.0, 0.0]);
        let q = robot.ik(&grasp, robot.ready()).unwrap();
        let held = Held::new(
            "block_a",
            block.shape.clone(),
            grasp.inverse() * block.pose,
            &Margins {
                held: 0.001,
                ..model.margins()
            },
        );
        let scene = Scene::new(&task.world, &["block_a"]);
        let checker = Checker::new(&robot, &model, &scene);
        assert_eq!(
            checker.check(&q, 0.05, Some(&held), &none()),
            Some(Hit::HeldWorld("block_a".into(), "shelf_1".into()))
        );
        let allow = Allowances {
            held_may_touch: vec!["shelf_1".into()],
            ..Allowances::default()
        };
        assert_eq!(checker.check(&q, 0.05, Some(&held), &allow), None);
    }

    /// The edge that turns the base joint from `by` radians one way of the ready pose to
    /// `by` the other way.
    fn base_turned_about_ready(robot: &Robot, by: f64) -> (Vec<f64>, Vec<f64>) {
        let mut a = robot.ready().to_vec();
        let mut b = a.clone();
        a[0] -= by;
        b[0] += by;
        (a, b)
    }

    /// A block in the hand's palm at the middle of an edge: the screen finds the hand in it
    /// at a point it screens (balls inside the hand reach it there, a quarter of the way,
    /// so no exact test is needed), and where the hand may touch the block the screen and
    /// the proof find nothing.
    #[test]
    fn screening_keeps_to_what_the_hand_may_touch() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let (a, b) = base_turned_about_ready(&robot, 0.3);
        let hand = robot
            .links()
            .iter()
            .position(|l| l.name == "fer_hand")
            .unwrap();
        let palm = robot.link_poses(robot.ready(), 0.08)[hand]
            * akl_tsr::nalgebra::Point3::new(0.0, 0.0, 0.04);
        let world = pick_place_with_box("block", [0.02; 3], [palm.x, palm.y, palm.z]);
        let scene = Scene::new(&world, &[]);
        let checker = Checker::new(&robot, &model, &scene);
        match checker.screen(&a, &b, 0.08, &none(), 3) {
            Some(Hit::World(link, object)) => {
                assert_eq!((link.as_str(), object.as_str()), ("fer_hand", "block"));
            }
            other => panic!("expected the hand in the block, got {other:?}"),
        }
        let may_touch = Allowances {
            hand_may_touch: vec!["block".into()],
            ..Allowances::default()
        };
        assert_eq!(checker.screen(&a, &b, 0.08, &may_touch, 8), None);
        assert_eq!(
            checker.screened_edge(&a, &b, 0.08, None, &may_touch, 8),
            None
        );
    }

    /// Screening finds a post in the way of an edge whose ends are free, at the edge's
    /// middle (its second point), and reports what hit it; with one point, the end, which it
    /// leaves to the edge's plain check, it finds nothing, and the proof alone finds the post
    /// too. An end beyond the joint limits is reported as such.
    #[test]
    fn screening_finds_a_collision_inside_an_edge_whose_ends_are_free() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let (a, b) = base_turned_about_ready(&robot, 0.6);
        let tcp = robot.tcp_pose(robot.ready()).translation.vector;
        let world = pick_place_with_box("post", [0.03, 0.03, 0.3], [tcp.x, tcp.y, tcp.z]);
        let scene = Scene::new(&world, &[]);
        let checker = Checker::new(&robot, &model, &scene);
        assert_eq!(checker.check(&a, 0.08, None, &none()), None);
        assert_eq!(checker.check(&b, 0.08, None, &none()), None);
        assert_eq!(checker.screen(&a, &b, 0.08, &none(), 1), None);
        let mut beyond = b.clone();
        beyond[0] = robot.joint_limits()[0][1] + 0.1;
        assert_eq!(
            checker.screened_edge(&a, &beyond, 0.08, None, &none(), 1),
            Some(Hit::Limits)
        );
        for hit in [
            checker.screen(&a, &b, 0.08, &none(), 2),
            checker.edge(&a, &b, 0.08, None, &none()),
        ] {
            match hit {
                Some(Hit::World(_, object)) => assert_eq!(object, "post"),
                other => panic!("expected the post, got {other:?}"),
            }
        }
    }

    /// An edge's ends keep their whole margins where the rest of it keeps half: a plate just
    /// inside the hand's margin under the fingers at the edge's start rejects the edge (at
    /// either end), while the same edge from a start taken as known to be valid, as a search
    /// takes its nodes, is proved free (the fingers leave the plate at once).
    #[test]
    fn edges_keep_the_whole_margin_at_their_ends() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let a = robot.ready().to_vec();
        let mut b = a.clone();
        b[1] -= 0.3;
        let world = plate_just_within_the_margin(&robot, &model, &a);
        let scene = Scene::new(&world, &[]);
        let checker = Checker::new(&robot, &model, &scene);
        assert_eq!(checker.check(&b, 0.08, None, &none()), None);
        for edge in [
            checker.edge(&a, &b, 0.08, None, &none()),
            checker.edge(&b, &a, 0.08, None, &none()),
            checker.screened_edge(&b, &a, 0.08, None, &none(), 0),
        ] {
            match edge {
                Some(Hit::World(_, object)) => assert_eq!(object, "plate"),
                other => panic!("expected the plate, got {other:?}"),
            }
        }
        assert_eq!(checker.screened_edge(&a, &b, 0.08, None, &none(), 0), None);
    }

    /// A hand that slides just clear of a plate (5.5 mm, its grown shape 0.5 mm) is proved
    /// free in a few checks, where the bound on its motion in any direction takes 32 probes:
    /// only motion across the plate's face can close the gap. A bump on the plate at the
    /// middle of the slide, 1.5 mm from a finger, past half the hand's margin, still rejects
    /// the edge (a control: the slab across the plate's face must not hide what stands on
    /// it).
    #[test]
    fn a_slide_along_a_face_is_proved_by_the_motion_across_it() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let (a, b) = base_turned_about_ready(&robot, 0.2);
        let mut world = plate_just_within_the_margin(&robot, &model, robot.ready());
        let plate = world.objects.pop().unwrap();
        let lowered = |by: f64| {
            let mut lowered = plate.clone();
            lowered.pose.translation.vector.z -= by;
            lowered
        };
        let probes = std::cell::Cell::new(0);
        world.objects.push(lowered(0.0005));
        let scene = Scene::new(&world, &[]);
        let checker = Checker::new(&robot, &model, &scene).counting(&probes);
        assert_eq!(checker.check(&a, 0.08, None, &none()), None);
        probes.set(0);
        assert_eq!(checker.screened_edge(&a, &b, 0.08, None, &none(), 0), None);
        assert!(probes.get() <= 4, "{} probes", probes.get());
        // The bump: 2 cm square, its top 4 mm above the plate's, under the left finger at
        // the middle of the slide (the ready pose).
        let finger = robot
            .links()
            .iter()
            .position(|l| l.name == "fer_leftfinger")
            .unwrap();
        let (poses, _) = checker.placements(robot.ready(), 0.08);
        let mut bump = lowered(0.0005 - 0.004);
        bump.name = "bump".into();
        bump.shape = akl_scene::Shape::Box {
            size: [0.02, 0.02, 0.01],
        };
        let under = poses[finger].translation.vector;
        bump.pose.translation.vector.x = under.x;
        bump.pose.translation.vector.y = under.y;
        world.objects.push(bump);
        let scene = Scene::new(&world, &[]);
        let checker = Checker::new(&robot, &model, &scene);
        for (from, to) in [(&a, &b), (&b, &a)] {
            assert_eq!(checker.check(to, 0.08, None, &none()), None);
            match checker.screened_edge(from, to, 0.08, None, &none(), 0) {
                Some(Hit::World(_, object)) => assert_eq!(object, "bump"),
                other => panic!("expected the bump, got {other:?}"),
            }
        }
    }

    /// The screen looks only for the arm's own certain collisions: a block that only the held
    /// object meets, at the middle of an edge, passes the screen at every point and is found
    /// by the proof (a control: screening must not be what rejects such edges).
    #[test]
    fn the_screen_leaves_the_held_object_to_the_proof() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let (a, b) = base_turned_about_ready(&robot, 0.4);
        let tcp = robot.tcp_pose(robot.ready());
        let in_tcp = Pose::from_parts([0.0, 0.0, 0.1].into(), Default::default());
        let centre = (tcp * in_tcp).translation.vector;
        let ball = akl_scene::Shape::Sphere { radius: 0.03 };
        let held = Held::new("ball", ball, in_tcp, &model.margins());
        let world = pick_place_with_box("block", [0.02; 3], [centre.x, centre.y, centre.z]);
        let scene = Scene::new(&world, &[]);
        let checker = Checker::new(&robot, &model, &scene);
        assert_eq!(checker.check(robot.ready(), 0.08, None, &none()), None);
        assert_eq!(checker.screen(&a, &b, 0.08, &none(), 8), None);
        for hit in [
            checker.check(robot.ready(), 0.08, Some(&held), &none()),
            checker.screened_edge(&a, &b, 0.08, Some(&held), &none(), 8),
        ] {
            assert_eq!(hit, Some(Hit::HeldWorld("ball".into(), "block".into())));
        }
    }

    fn arb_q() -> impl Strategy<Value = Vec<f64>> {
        let robot = Robot::panda().unwrap();
        robot
            .joint_limits()
            .iter()
            .map(|[lo, hi]| *lo..*hi)
            .collect::<Vec<_>>()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// An edge reported free keeps half of every margin (between links too) at a re-check
        /// dense enough that no point moves more than a tenth of the smallest margin.
        #[test]
        fn free_edges_keep_half_their_margins_everywhere(a in arb_q(), b in arb_q(), t in 0.0..1.0f64) {
            let robot = Robot::panda().unwrap();
            let model = RobotCollision::new(&robot);
            let m = model.margins();
            let half = RobotCollision::with_margins(&robot, Margins {
                arm: m.arm / 2.0, hand: m.hand / 2.0, held: m.held / 2.0, self_: m.self_ / 2.0,
            });
            let task = builtin::task("inspection").unwrap().unwrap();
            let scene = Scene::new(&task.world, &[]);
            let checker = Checker::new(&robot, &model, &scene);
            let dense = Checker::new(&robot, &half, &scene);
            // Shorten the edge so that a good share of them are free.
            let b: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x + t * 0.5 * (y - x)).collect();
            if checker.edge(&a, &b, 0.08, None, &none()).is_none() {
                let smallest = m.arm.min(m.hand).min(m.self_ / 2.0);
                let n = (10.0 * checker.sweep_bound(&a, &b, 0.08, None) / smallest).ceil() as usize;
                for k in 0..=n {
                    let s = k as f64 / n.max(1) as f64;
                    let q: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x + s * (y - x)).collect();
                    prop_assert_eq!(dense.check(&q, 0.08, None, &none()), None);
                }
            }
        }
    }
}

mod parry_false_positive {
    use super::*;

    /// A configuration where parry's intersection test alone reports the hand's capsule
    /// (inflated by half its margin) as touching block_b while it is 2.8 mm away (found by
    /// the RRT dense re-check with seed 82996): the checker must call it free.
    #[test]
    fn a_capsule_millimetres_from_a_box_is_not_a_collision() {
        let robot = Robot::panda().unwrap();
        let full = RobotCollision::new(&robot);
        let m = full.margins;
        let half = RobotCollision::with_margins(
            &robot,
            Margins {
                arm: m.arm / 2.0,
                hand: m.hand / 2.0,
                held: m.held / 2.0,
                self_: m.self_ / 2.0,
            },
        );
        let world = akl_scene::builtin::task("pick_place")
            .unwrap()
            .unwrap()
            .world;
        let scene = Scene::new(&world, &[]);
        let q = [
            1.649183, 0.854644, -1.19825, -1.952202, -1.082712, 2.778365, -0.502894,
        ];
        let checker = Checker::new(&robot, &half, &scene);
        assert_eq!(
            checker.check(&q, robot.open_width(), None, &Allowances::default()),
            None
        );
        let n = robot.links().len();
        let mut poses = vec![Pose::identity(); n];
        robot
            .kinematics()
            .link_poses_into(&q, robot.open_width(), &mut poses);
        let block = scene
            .obstacles
            .iter()
            .find(|o| o.name == "block_b")
            .unwrap();
        let hand = half
            .bodies
            .iter()
            .find(|b| robot.links()[b.link].name == "fer_hand")
            .unwrap();
        let at = placed(hand, &(scene.base * poses[hand.link]));
        let d = parry_convert::distance(&hand.world_shape, &at.pose, &block.shape, &block.pose);
        assert!(d.unwrap() > 0.002, "{d:?}");
        assert!(!parry_convert::intersects(
            &hand.world_shape,
            &at.pose,
            &block.shape,
            &block.pose
        ));
    }
}

/// The culled check against parry's exact test of every pair it must test.
mod exhaustive {
    use super::*;
    use crate::contact_rules;
    use akl_scene::builtin;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    /// The bounds (boxes, segments, balls) never turn a collision into a free verdict nor
    /// the reverse: 3,000 random configurations per built-in scene.
    #[test]
    fn plain_checks_match_exact_tests_of_every_pair() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let allow = Allowances::default();
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        for name in builtin::names() {
            let task = builtin::task(name).unwrap().unwrap();
            let scene = Scene::new(&task.world, &[]);
            let checker = Checker::new(&robot, &model, &scene);
            let mut differ = 0;
            for _ in 0..3000 {
                let q: Vec<f64> = robot
                    .joint_limits()
                    .iter()
                    .map(|[lo, hi]| rng.gen_range(*lo..*hi))
                    .collect();
                let (_, placed_bodies) = checker.placements(&q, 0.08);
                let mut world_hit = false;
                for (b, p) in model.bodies.iter().zip(&placed_bodies) {
                    for o in &scene.obstacles {
                        if contact_rules::link_may_touch(
                            model.role(b),
                            &o.name,
                            None,
                            scene.mount(),
                            &allow,
                        ) {
                            continue;
                        }
                        if parry_convert::intersects(&b.world_shape, &p.pose, &o.shape, &o.pose) {
                            world_hit = true;
                        }
                    }
                }
                let mut self_hit = false;
                for &(i, j) in &model.self_pairs {
                    if parry_convert::intersects(
                        &model.bodies[i].self_shape,
                        &placed_bodies[i].pose,
                        &model.bodies[j].self_shape,
                        &placed_bodies[j].pose,
                    ) {
                        self_hit = true;
                    }
                }
                let exact_free = !world_hit && !self_hit;
                if checker.is_free(&q, 0.08, None, &allow) != exact_free {
                    differ += 1;
                }
            }
            assert_eq!(differ, 0, "{name}");
        }
    }
}

/// parry's double-precision intersection test, trusted by [`parry_convert::intersects`] without
/// a second query, never calls shapes intersecting that a certified slab separates: the Panda's
/// grown hulls against boxes and against each other, placed within 3 mm of contact in random
/// directions and turns (300,000 placements when this was measured: none; single precision
/// had called a capsule 2.8 mm from a block intersecting).
#[test]
fn the_intersection_test_has_no_false_positives_near_contact() {
    use akl_tsr::nalgebra::{Translation3, UnitQuaternion, Vector3};
    use parry3d_f64::shape::SharedShape;
    use rand::{Rng, SeedableRng};
    let robot = Robot::panda().unwrap();
    let model = RobotCollision::new(&robot);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
    let boxes = [
        SharedShape::cuboid(0.2, 0.1, 0.02),
        SharedShape::cuboid(0.03, 0.03, 0.03),
    ];
    let at = |pose: &Pose| parry_convert::pose(pose);
    let mut hits = 0;
    for _ in 0..3000 {
        let a = &model.bodies[rng.gen_range(0..model.bodies.len())].world_shape;
        let b = if rng.gen_bool(0.5) {
            boxes[rng.gen_range(0..2)].clone()
        } else {
            model.bodies[rng.gen_range(0..model.bodies.len())]
                .world_shape
                .clone()
        };
        let turn = UnitQuaternion::from_euler_angles(
            rng.gen_range(-3.0..3.0),
            rng.gen_range(-3.0..3.0),
            rng.gen_range(-3.0..3.0),
        );
        let dir = Vector3::new(
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
        )
        .normalize();
        let placed = |d: f64| Pose::from_parts(Translation3::from(dir * d), turn);
        let apart =
            |d: f64| parry_convert::distance(a, &Pose::identity(), &b, &placed(d)).unwrap() > 0.0;
        let (mut lo, mut hi) = (0.0, 0.6);
        for _ in 0..30 {
            let mid = 0.5 * (lo + hi);
            if apart(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let d = hi + rng.gen_range(-0.003..0.003);
        let hit = parry3d_f64::query::intersection_test(
            &at(&Pose::identity()),
            a.as_ref(),
            &at(&placed(d)),
            b.as_ref(),
        )
        .unwrap()
        .intersecting;
        assert!(!(hit && apart(d)), "called intersecting {d} m out");
        hits += usize::from(hit);
    }
    assert!(hits > 1000, "only {hits} placements intersect");
}

mod motion_bounds {
    use super::super::checker::{LinkPoses, PlacedBodies};
    use super::super::model::chain_to;
    use super::super::sweep::Sweep;
    use super::*;
    use akl_scene::builtin;
    use akl_tsr::nalgebra::{Point3, Vector3};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A random configuration and a random stretch about it (up to 1.5 rad per joint) with
    /// its bounds written into `sweep`; the link poses and placed elements at the
    /// configuration; a share f of the stretch, and f signed by the side it is taken on.
    fn random_stretch(
        checker: &Checker,
        limits: &[[f64; 2]],
        rng: &mut ChaCha8Rng,
        sweep: &mut Sweep,
    ) -> (Vec<f64>, LinkPoses, PlacedBodies, f64, f64) {
        let q: Vec<f64> = limits
            .iter()
            .map(|[lo, hi]| rng.gen_range(*lo..*hi))
            .collect();
        let size = rng.gen_range(0.01..1.5);
        for i in 0..q.len() {
            sweep.step[i] = size * rng.gen_range(-1.0..1.0);
        }
        let (poses, placed_bodies) = checker.placements(&q, 0.08);
        checker.sweep_bounds(&poses, &placed_bodies, None, sweep);
        let f: f64 = rng.gen_range(0.0..=1.0);
        let side = if rng.gen_bool(0.5) { f } else { -f };
        (q, poses, placed_bodies, f, side)
    }

    /// The motion bound of every chain, from every joint on, holds along the stretch: a point
    /// within the element's extent of its centre, moved by the chain's joints from that one
    /// on (the others held, as the frame before it is then fixed) by any share f of the
    /// stretch either way, moves no further than the bound at f. Stretches of up to 1.5 rad
    /// per joint, where the terms beyond the first order matter most.
    #[test]
    fn every_point_of_an_element_moves_within_its_bound() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let task = builtin::task("pick_place").unwrap().unwrap();
        let scene = Scene::new(&task.world, &[]);
        let checker = Checker::new(&robot, &model, &scene);
        let limits = robot.joint_limits();
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut sweep = Sweep::new(&model, robot.dof());
        let mut tight = 0usize;
        for case in 0..400 {
            let (q, poses, placed_bodies, f, side) =
                random_stretch(&checker, limits, &mut rng, &mut sweep);
            for (k, (body, placed_body)) in model.bodies.iter().zip(&placed_bodies).enumerate() {
                let chain = &chain_to(robot.kinematics(), body.link);
                let extent = body.half_segment + body.core_radius;
                let direction = Vector3::new(
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                )
                .normalize();
                let at = placed_body.pose.translation.vector + extent * direction;
                let local = poses[body.link].inverse() * Point3::from(at);
                for m in 0..=chain.len() {
                    let mut moved = q.clone();
                    for mover in &chain[m..] {
                        moved[mover.index] = q[mover.index] + side * sweep.step[mover.index];
                    }
                    let (after, _) = checker.placements(&moved, 0.08);
                    let distance = ((after[body.link] * local).coords - at).norm();
                    let bound = sweep.bounds[model.offsets[k] + m].at(f);
                    assert!(
                        distance <= bound + 1e-9,
                        "case {case}, element {k}, from joint {m}: moved {distance} beyond {bound}"
                    );
                    tight += usize::from(distance > 0.5 * bound);
                }
            }
        }
        // Not vacuous: the bound is often within a factor of two of the motion.
        assert!(
            tight > 1000,
            "only {tight} motions came within half their bound"
        );
    }

    /// The bound on motion along a direction holds along the stretch: a point within the
    /// element's extent of its centre, moved by the whole chain by any share f of the stretch
    /// either way, moves along any unit vector no further than the bound at f. It is what a
    /// gap across a slab of that direction is held to, so it must hold for every direction,
    /// though it is smallest for those the element moves across.
    #[test]
    fn every_point_of_an_element_moves_along_a_direction_within_its_bound() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let task = builtin::task("pick_place").unwrap().unwrap();
        let scene = Scene::new(&task.world, &[]);
        let checker = Checker::new(&robot, &model, &scene);
        let limits = robot.joint_limits();
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut sweep = Sweep::new(&model, robot.dof());
        let unit = |rng: &mut ChaCha8Rng| {
            Vector3::new(
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
            )
            .normalize()
        };
        let (mut tight, mut smaller) = (0usize, 0usize);
        for case in 0..400 {
            let (q, poses, placed_bodies, f, side) =
                random_stretch(&checker, limits, &mut rng, &mut sweep);
            let moved: Vec<f64> = q
                .iter()
                .zip(&sweep.step)
                .map(|(x, s)| x + side * s)
                .collect();
            let (after, _) = checker.placements(&moved, 0.08);
            for (k, (body, placed_body)) in model.bodies.iter().zip(&placed_bodies).enumerate() {
                let extent = body.half_segment + body.core_radius;
                let at = placed_body.pose.translation.vector + extent * unit(&mut rng);
                let local = poses[body.link].inverse() * Point3::from(at);
                let shift = (after[body.link] * local).coords - at;
                // Half the time the direction the point moves in, the worst case for the bound.
                let n = if rng.gen_bool(0.5) {
                    shift.try_normalize(1e-12).unwrap_or_else(|| unit(&mut rng))
                } else {
                    unit(&mut rng)
                };
                let along = shift.dot(&n).abs();
                let carried = sweep.carried[model.offsets[k]].along(&n);
                let bound = carried.at(f);
                assert!(
                    along <= bound + 1e-9,
                    "case {case}, element {k}: moved {along} along {n:?} beyond {bound}"
                );
                tight += usize::from(along > 0.5 * bound);
                smaller += usize::from(bound < 0.5 * sweep.bounds[model.offsets[k]].at(f));
            }
        }
        // Not vacuous, and of use: often within a factor of two of the motion, and often less
        // than half the bound on the motion in any direction.
        assert!(
            tight > 1000,
            "only {tight} motions came within half their bound"
        );
        assert!(
            smaller > 300,
            "only {smaller} bounds along a direction were below half"
        );
    }
}
