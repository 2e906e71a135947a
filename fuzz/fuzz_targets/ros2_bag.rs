//! A ROS 2 bag (MCAP with CDR messages): `import_ros2` with the topics the seed bags use (the
//! hand on a PoseStamped topic, one object on the transform tree, the gripper's joint states).
#![no_main]

use akl_learn::{import_ros2, PoseSource, Ros2Topics};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let topics = Ros2Topics {
        task: "pick".into(),
        frame: "base".into(),
        ee: PoseSource::parse("/ee_pose"),
        objects: vec![("part".into(), PoseSource::parse("tf:part"))],
        gripper: "/joint_states".into(),
        closed_below: 0.075,
    };
    let _ = import_ros2(data, &topics);
});
