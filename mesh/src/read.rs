//! Reading triangle meshes from files.

use crate::MeshError;
use akl_tsr::nalgebra::Point3;
use std::path::Path;

/// Triangles read from a mesh file: vertices (metres, in the file's frame) and, for each
/// triangle, the indices of its three vertices.
#[derive(Debug, Clone, PartialEq)]
pub struct TriMesh {
    /// The vertices.
    pub vertices: Vec<Point3<f64>>,
    /// The triangles, as vertex indices.
    pub triangles: Vec<[u32; 3]>,
}

/// The triangles of the STL, OBJ or COLLADA file at `path`, every mesh in it merged into one.
/// Errors name the file.
pub fn load(path: &Path) -> Result<TriMesh, MeshError> {
    let bytes = std::fs::read(path).map_err(|e| MeshError::Read {
        path: path.to_path_buf(),
        problem: e.to_string(),
    })?;
    load_bytes(&bytes, path)
}

/// The triangles of a mesh file's contents (`bytes`), its format told by the extension of
/// `path`, which also names it in errors: for meshes built into the binary.
pub fn load_bytes(bytes: &[u8], path: &Path) -> Result<TriMesh, MeshError> {
    let read_error = |problem: String| MeshError::Read {
        path: path.to_path_buf(),
        problem,
    };
    let scene = mesh_loader::Loader::default()
        .merge_meshes(true)
        .load_from_slice(bytes, path)
        .map_err(|e| read_error(e.to_string()))?;
    let mut mesh = TriMesh {
        vertices: Vec::new(),
        triangles: Vec::new(),
    };
    for m in scene.meshes {
        let offset = mesh.vertices.len() as u32;
        mesh.vertices.extend(
            m.vertices
                .iter()
                .map(|v| Point3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]))),
        );
        mesh.triangles
            .extend(m.faces.iter().map(|f| f.map(|i| i + offset)));
    }
    if mesh.vertices.is_empty() {
        return Err(read_error("it holds no vertices".into()));
    }
    if let Some(bad) = mesh
        .vertices
        .iter()
        .position(|v| !v.coords.iter().all(|c| c.is_finite()))
    {
        return Err(read_error(format!("vertex {bad} is not finite")));
    }
    if let Some(bad) = mesh
        .triangles
        .iter()
        .position(|t| t.iter().any(|&i| i as usize >= mesh.vertices.len()))
    {
        return Err(read_error(format!(
            "triangle {bad} names a vertex it does not have"
        )));
    }
    Ok(mesh)
}

impl TriMesh {
    /// Each triangle as its three corners.
    pub fn corners(&self) -> impl Iterator<Item = [Point3<f64>; 3]> + '_ {
        self.triangles
            .iter()
            .map(|t| t.map(|i| self.vertices[i as usize]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str, text: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("akl-mesh-read-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    const TETRAHEDRON_OBJ: &str =
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

    #[test]
    fn an_obj_and_an_ascii_stl_are_read() {
        let obj = load(&scratch("t.obj", TETRAHEDRON_OBJ)).unwrap();
        // The reader gives each triangle its own three vertices.
        assert_eq!(obj.triangles.len(), 4);
        let mut distinct = obj.vertices.clone();
        distinct.sort_by(|a, b| {
            a.coords
                .as_slice()
                .partial_cmp(b.coords.as_slice())
                .unwrap()
        });
        distinct.dedup();
        assert_eq!(distinct.len(), 4);
        assert!(obj.vertices.contains(&Point3::new(0.0, 0.0, 1.0)));
        let stl = "solid t\n facet normal 0 0 -1\n  outer loop\n   vertex 0 0 0\n   vertex 0 1 0\n   vertex 1 0 0\n  endloop\n endfacet\nendsolid t\n";
        let stl = load(&scratch("t.stl", stl)).unwrap();
        assert_eq!(stl.triangles.len(), 1);
        assert_eq!(stl.vertices.len(), 3);
    }

    #[test]
    fn a_missing_or_unreadable_file_is_named() {
        let e = load(Path::new("no/such/part.stl")).unwrap_err().to_string();
        assert!(e.contains("no/such/part.stl"), "{e}");
        let e = load(&scratch("x.xyz", "nothing")).unwrap_err().to_string();
        assert!(e.contains("x.xyz"), "{e}");
    }
}
