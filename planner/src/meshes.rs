//! The robot's link meshes: the URDF's `<mesh>` elements (collision and visual) resolved to
//! files, read through `akl-mesh`, scaled and placed in their link's frame.
//!
//! A mesh's `filename` is resolved as ROS tools resolve it: `package://NAME/PATH` through the
//! package folders given (`--package-path NAME=DIR`, then the robot folder's `[packages]`
//! table, then `ROS_PACKAGE_PATH`), `file://PATH` as a path, anything else relative to the
//! URDF's folder. The built-in Panda's meshes are embedded in the binary.

use crate::error::MeshFailure;
use crate::fk::Kinematics;
use akl_mesh::TriMesh;
use akl_tsr::nalgebra::{Point3, Vector3};
use akl_tsr::pose::pose_from_xyz_rpy;
use akl_tsr::Pose;
use std::path::{Component, Path, PathBuf};

/// Which of a link's URDF elements a mesh comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MeshRole {
    /// A `<collision>` element: what the vendor says the link collides as.
    Collision,
    /// A `<visual>` element: what the link looks like.
    Visual,
}

/// One mesh of a link, its triangles in the link's frame (scaled and placed by the element's
/// origin).
#[derive(Debug, Clone)]
pub struct LinkMesh {
    /// Robot link index.
    pub link: usize,
    /// Collision or visual element.
    pub role: MeshRole,
    /// The URDF's `filename`.
    pub uri: String,
    /// The triangles, in the link's frame (metres).
    pub mesh: TriMesh,
}

/// Mesh files built into the binary, by their path relative to the robot folder.
pub(crate) type EmbeddedFiles = &'static [(&'static str, &'static [u8])];

/// Where mesh files are found: the robot folder (on disk or embedded), the URDF's folder
/// and the package folders.
#[derive(Debug, Clone)]
pub(crate) struct MeshFiles {
    /// The robot folder; paths below it are read from `embedded` when that is given.
    robot_dir: PathBuf,
    /// The URDF's folder, for relative file names.
    urdf_dir: PathBuf,
    /// Package folders by name, first match wins.
    packages: Vec<(String, PathBuf)>,
    /// The files of a built-in robot.
    embedded: Option<EmbeddedFiles>,
}

/// A ROS package name and its folder, as `--package-path NAME=DIR` gives it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PackagePath {
    /// The package name.
    pub name: String,
    /// Its folder.
    pub dir: PathBuf,
}

impl std::str::FromStr for PackagePath {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        match text.split_once('=') {
            Some((name, dir)) if !name.trim().is_empty() && !dir.trim().is_empty() => {
                Ok(PackagePath {
                    name: name.trim().to_string(),
                    dir: PathBuf::from(dir.trim()),
                })
            }
            _ => Err(format!("`{text}` is not NAME=DIR (e.g. franka_description=/opt/ros/share/franka_description)")),
        }
    }
}

impl MeshFiles {
    /// Mesh files of the robot folder `robot_dir` whose URDF lies in `urdf_dir`: the package
    /// folders given first, then the folder's own `[packages]` (relative to it), then
    /// `ROS_PACKAGE_PATH`.
    pub(crate) fn new(
        robot_dir: &Path,
        urdf_dir: &Path,
        given: &[PackagePath],
        own: &[(String, String)],
        embedded: Option<EmbeddedFiles>,
    ) -> MeshFiles {
        let mut packages: Vec<(String, PathBuf)> = given
            .iter()
            .map(|p| (p.name.clone(), p.dir.clone()))
            .collect();
        packages.extend(
            own.iter()
                .map(|(name, dir)| (name.clone(), robot_dir.join(dir))),
        );
        MeshFiles {
            robot_dir: robot_dir.to_path_buf(),
            urdf_dir: urdf_dir.to_path_buf(),
            packages,
            embedded,
        }
    }

    /// The folder of package `name`, if known.
    fn package(&self, name: &str) -> Option<PathBuf> {
        if let Some((_, dir)) = self.packages.iter().find(|(n, _)| n == name) {
            return Some(dir.clone());
        }
        let ros = std::env::var_os("ROS_PACKAGE_PATH")?;
        std::env::split_paths(&ros).find_map(|dir| {
            if dir.file_name().is_some_and(|f| f == name) && dir.is_dir() {
                Some(dir)
            } else {
                let inner = dir.join(name);
                inner.is_dir().then_some(inner)
            }
        })
    }

    /// The path a URDF `filename` names.
    fn resolve(&self, uri: &str) -> Result<PathBuf, String> {
        if let Some(rest) = uri.strip_prefix("package://") {
            let (name, path) = rest
                .split_once('/')
                .ok_or_else(|| format!("`{uri}` names no file inside its package"))?;
            let dir = self.package(name).ok_or_else(|| {
                format!(
                    "package `{name}` is not known: give --package-path {name}=DIR, list it under [packages] in robot.toml, or put its parent folder on ROS_PACKAGE_PATH"
                )
            })?;
            return Ok(dir.join(path));
        }
        if let Some(path) = uri.strip_prefix("file://") {
            return Ok(PathBuf::from(path));
        }
        if uri.contains("://") {
            return Err(format!(
                "`{uri}`: only package:// and file:// URIs are read"
            ));
        }
        Ok(self.urdf_dir.join(uri))
    }

    /// Reads the mesh `uri` names.
    fn read(&self, uri: &str) -> Result<TriMesh, String> {
        let path = self.resolve(uri)?;
        if let Some(files) = self.embedded {
            let inside = normalize(&path)
                .strip_prefix(normalize(&self.robot_dir))
                .map(Path::to_path_buf)
                .ok();
            let found = inside.as_ref().and_then(|rel| {
                files
                    .iter()
                    .find(|(name, _)| Path::new(name) == rel.as_path())
            });
            return match found {
                Some((_, bytes)) => akl_mesh::load_bytes(bytes, &path).map_err(|e| e.to_string()),
                None => Err(format!("{}: not built into the binary", path.display())),
            };
        }
        akl_mesh::load(&path).map_err(|e| e.to_string())
    }
}

/// `path` without `.` components and with `..` applied where it can be.
fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                if !out.pop() {
                    out.push("..");
                }
            }
            other => out.push(other),
        }
    }
    out
}

/// Every mesh element of the URDF's links, read and placed in its link's frame. The error
/// lists every mesh that cannot be read, not only the first.
pub(crate) fn read_link_meshes(
    urdf: &urdf_rs::Robot,
    kin: &Kinematics,
    files: &MeshFiles,
) -> Result<Vec<LinkMesh>, Vec<MeshFailure>> {
    let mut meshes = Vec::new();
    let mut problems = Vec::new();
    for link in &urdf.links {
        let Some(index) = kin.link_index(&link.name) else {
            continue;
        };
        let elements = link
            .collision
            .iter()
            .map(|c| (MeshRole::Collision, &c.origin, &c.geometry))
            .chain(
                link.visual
                    .iter()
                    .map(|v| (MeshRole::Visual, &v.origin, &v.geometry)),
            );
        for (role, origin, geometry) in elements {
            let urdf_rs::Geometry::Mesh { filename, scale } = geometry else {
                continue;
            };
            match files.read(filename) {
                Ok(mesh) => {
                    let origin = pose_from_xyz_rpy(*origin.xyz, *origin.rpy);
                    let scale = scale.map_or(Vector3::repeat(1.0), |s| Vector3::from(*s));
                    meshes.push(LinkMesh {
                        link: index,
                        role,
                        uri: filename.clone(),
                        mesh: placed(mesh, &origin, &scale),
                    });
                }
                Err(problem) => problems.push(MeshFailure {
                    link: link.name.clone(),
                    uri: filename.clone(),
                    problem,
                }),
            }
        }
    }
    if problems.is_empty() {
        Ok(meshes)
    } else {
        Err(problems)
    }
}

/// The mesh scaled by `scale` in its own frame, then placed by `origin`.
fn placed(mut mesh: TriMesh, origin: &Pose, scale: &Vector3<f64>) -> TriMesh {
    for v in &mut mesh.vertices {
        *v = origin * Point3::from(v.coords.component_mul(scale));
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    fn files(given: &[PackagePath], own: &[(String, String)]) -> MeshFiles {
        MeshFiles::new(
            Path::new("/robots/r"),
            Path::new("/robots/r/urdf"),
            given,
            own,
            None,
        )
    }

    #[test]
    fn package_uris_resolve_through_given_then_own_packages() {
        let own = [("pkg".to_string(), "vendor/pkg".to_string())];
        let f = files(&[], &own);
        assert_eq!(
            f.resolve("package://pkg/meshes/a.stl").unwrap(),
            Path::new("/robots/r/vendor/pkg/meshes/a.stl")
        );
        let given = ["pkg=/opt/pkg".parse::<PackagePath>().unwrap()];
        let f = files(&given, &own);
        assert_eq!(
            f.resolve("package://pkg/meshes/a.stl").unwrap(),
            Path::new("/opt/pkg/meshes/a.stl")
        );
        assert_eq!(
            f.resolve("meshes/b.stl").unwrap(),
            Path::new("/robots/r/urdf/meshes/b.stl")
        );
        assert_eq!(f.resolve("file:///m/c.stl").unwrap(), Path::new("/m/c.stl"));
    }

    #[test]
    fn unknown_packages_and_schemes_say_what_to_do() {
        let f = files(&[], &[]);
        let e = f.resolve("package://nowhere_pkg_xyz/a.stl").unwrap_err();
        assert!(e.contains("--package-path nowhere_pkg_xyz=DIR"), "{e}");
        let e = f.resolve("http://example.com/a.stl").unwrap_err();
        assert!(e.contains("only package:// and file://"), "{e}");
        assert!("nodir".parse::<PackagePath>().is_err());
        assert!("=x".parse::<PackagePath>().is_err());
    }

    #[test]
    fn paths_normalize_before_embedded_lookup() {
        assert_eq!(
            normalize(Path::new("robots/panda/./meshes/../meshes/a.stl")),
            Path::new("robots/panda/meshes/a.stl")
        );
    }
}
