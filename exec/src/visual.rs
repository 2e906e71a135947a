//! The robot as it looks, for traces: each link's visual meshes as a Foxglove model (binary
//! STL embedded in the message), locked to the link's frame, so a trace shows the real arm
//! beside the collision model that was checked.

use akl_foxglove::{Model, SceneEntity, SceneUpdate, Vector3};
use akl_planner::MeshRole;
use akl_planner::Robot;
use akl_tsr::Pose;
use base64::Engine as _;

/// The colour the visual meshes are drawn in (their own materials are not read).
const LOOK: [f64; 4] = [0.93, 0.93, 0.95, 1.0];

/// A scene update with one entity per link that has visual meshes; `None` when the robot
/// has none (a URDF of primitives).
pub(crate) fn robot_models(robot: &Robot) -> Option<SceneUpdate> {
    let links = robot.links();
    let entities: Vec<SceneEntity> = (0..links.len())
        .filter_map(|i| {
            let meshes: Vec<_> = robot
                .meshes()
                .iter()
                .filter(|m| m.link == i && m.role == MeshRole::Visual)
                .collect();
            if meshes.is_empty() {
                return None;
            }
            let stl = binary_stl(meshes.iter().flat_map(|m| m.mesh.corners()));
            let model = Model {
                pose: (&Pose::identity()).into(),
                scale: Vector3::uniform(1.0),
                color: LOOK.into(),
                override_color: true,
                url: String::new(),
                media_type: "model/stl".into(),
                data: base64::engine::general_purpose::STANDARD.encode(stl),
            };
            let id = format!("{} visual", links[i].name);
            Some(SceneEntity {
                frame_locked: true,
                models: vec![model],
                ..SceneEntity::new(0.0, &links[i].name, &id)
            })
        })
        .collect();
    (!entities.is_empty()).then(|| SceneUpdate::new(entities))
}

/// Triangles as a binary STL file (80-byte header, count, then per triangle a normal, three
/// corners and two attribute bytes, all little-endian single precision).
fn binary_stl(triangles: impl Iterator<Item = [akl_tsr::nalgebra::Point3<f64>; 3]>) -> Vec<u8> {
    let triangles: Vec<_> = triangles.collect();
    let mut out = Vec::with_capacity(84 + 50 * triangles.len());
    let mut header = [0u8; 80];
    let title = b"akl robot visual mesh";
    header[..title.len()].copy_from_slice(title);
    out.extend_from_slice(&header);
    out.extend_from_slice(&(triangles.len() as u32).to_le_bytes());
    for t in &triangles {
        let n = (t[1] - t[0]).cross(&(t[2] - t[0]));
        let n = if n.norm() > 0.0 { n.normalize() } else { n };
        for v in std::iter::once(n).chain(t.iter().map(|p| p.coords)) {
            for c in v.iter() {
                out.extend_from_slice(&(*c as f32).to_le_bytes());
            }
        }
        out.extend_from_slice(&[0, 0]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stl_reads_back_with_the_same_triangles() {
        let robot = Robot::panda().unwrap();
        let link = robot
            .meshes()
            .iter()
            .find(|m| m.role == MeshRole::Visual)
            .unwrap();
        let bytes = binary_stl(link.mesh.corners());
        let back = akl_mesh::load_bytes(&bytes, std::path::Path::new("x.stl")).unwrap();
        assert_eq!(back.triangles.len(), link.mesh.triangles.len());
        let first = link.mesh.corners().next().unwrap();
        let again = back.corners().next().unwrap();
        for (a, b) in first.iter().zip(&again) {
            assert!((a - b).norm() < 1e-6);
        }
    }

    #[test]
    fn every_panda_link_with_a_visual_mesh_gets_a_model() {
        let robot = Robot::panda().unwrap();
        let update = robot_models(&robot).unwrap();
        let ids: Vec<&str> = update
            .entities
            .iter()
            .map(|e| e.frame_id.as_str())
            .collect();
        // Links 0-7, the hand and both fingers.
        assert_eq!(ids.len(), 11, "{ids:?}");
        assert!(ids.contains(&"fer_link5") && ids.contains(&"fer_rightfinger"));
    }
}
