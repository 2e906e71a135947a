//! Object shapes a recording declares, so that learning can ground a release by the support
//! rule of a task world when no task world is at hand (a driver's stream, a ROS 2 bag).
//!
//! A JSONL or MCAP header carries them in its `shapes` field, a ROS 2 bag in a shapes file
//! given beside it: both map object names to shapes written as in a task file, e.g.
//! `{"table": {"type": "box", "size": [1.2, 1.4, 0.04]}, "can": {"type": "cylinder",
//! "radius": 0.03, "length": 0.12}, "tray": {"type": "mesh", "file": "tray.stl"}}`. A mesh
//! file is read relative to the folder of the file that declares it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use akl_scene::{Shape, ShapeError};

/// Why the declared shapes cannot be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ShapesError {
    /// A shape's size is not a positive finite length.
    #[error("the shape of `{object}`: {source}")]
    Invalid {
        /// The object whose shape it is.
        object: String,
        /// What is wrong with it.
        source: ShapeError,
    },
    /// A mesh file could not be read or has no solid hull.
    #[error("the shape of `{object}`: {source}")]
    Mesh {
        /// The object whose shape it is.
        object: String,
        /// What went wrong with the file (it names the file).
        source: akl_mesh::MeshError,
    },
    /// A shape is declared for an object the recording does not track.
    #[error("a shape is declared for `{object}`, which no frame tracks (tracked: {tracked})")]
    Untracked {
        /// The object named.
        object: String,
        /// The objects the recording tracks, comma-separated.
        tracked: String,
    },
}

/// Why a shapes file could not be read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ShapesFileError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The file is not a JSON object of shapes.
    #[error("{path}: line {line}, column {column}: {message}")]
    Json {
        /// The file.
        path: PathBuf,
        /// 1-based line of the problem.
        line: usize,
        /// 1-based column of the problem.
        column: usize,
        /// What is wrong.
        message: String,
    },
    /// A shape in it is unusable.
    #[error("{path}: {source}")]
    Shape {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        source: ShapesError,
    },
}

/// Makes `shapes` ready for learning from a recording that tracks `tracked`: every name must be
/// tracked, every mesh file (relative to `folder`) is read and renamed by its path from there,
/// and every size is checked. Errors name the object.
pub fn prepare_shapes(
    shapes: &mut BTreeMap<String, Shape>,
    folder: &Path,
    tracked: &[String],
) -> Result<(), ShapesError> {
    for (object, shape) in shapes.iter_mut() {
        if !tracked.contains(object) {
            return Err(ShapesError::Untracked {
                object: object.clone(),
                tracked: tracked.join(", "),
            });
        }
        shape.resolve(folder).map_err(|source| ShapesError::Mesh {
            object: object.clone(),
            source,
        })?;
        if let Shape::Mesh { file, .. } = shape {
            *file = folder.join(file.as_str()).display().to_string();
        }
        shape.validate().map_err(|source| ShapesError::Invalid {
            object: object.clone(),
            source,
        })?;
    }
    Ok(())
}

/// Reads a shapes file (a JSON object mapping object names to shapes) and prepares it for a
/// recording that tracks `tracked` (see [`prepare_shapes`]; meshes relative to the file).
pub fn read_shapes_file(
    path: &Path,
    tracked: &[String],
) -> Result<BTreeMap<String, Shape>, ShapesFileError> {
    let text = std::fs::read_to_string(path).map_err(|source| ShapesFileError::Io {
        path: path.into(),
        source,
    })?;
    let mut shapes: BTreeMap<String, Shape> = serde_json::from_str(&text).map_err(|e| {
        let (line, column, message) = akl_tsr::describe_json_error(&e, &text);
        ShapesFileError::Json {
            path: path.into(),
            line,
            column,
            message,
        }
    })?;
    let folder = path.parent().unwrap_or(Path::new(""));
    prepare_shapes(&mut shapes, folder, tracked).map_err(|source| ShapesFileError::Shape {
        path: path.into(),
        source,
    })?;
    Ok(shapes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tracked() -> Vec<String> {
        vec!["block".into(), "table".into()]
    }

    /// An OBJ file of a box of `size` centred on the origin: corner i has bit 0, 1, 2 of i set
    /// on its +x, +y, +z side; two triangles per face.
    fn box_obj(size: [f64; 3]) -> String {
        let mut text: String = (0..8)
            .map(|i: usize| {
                let c = |axis: usize| (if i >> axis & 1 == 1 { 0.5 } else { -0.5 }) * size[axis];
                format!("v {} {} {}\n", c(0), c(1), c(2))
            })
            .collect();
        for [a, b, c, d] in [
            [0, 2, 6, 4],
            [1, 3, 7, 5],
            [0, 1, 5, 4],
            [2, 3, 7, 6],
            [0, 1, 3, 2],
            [4, 5, 7, 6],
        ] {
            text += &format!(
                "f {} {} {}\nf {} {} {}\n",
                a + 1,
                b + 1,
                c + 1,
                a + 1,
                c + 1,
                d + 1
            );
        }
        text
    }

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("akl-shapes-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn a_shapes_file_reads_its_meshes_from_its_own_folder() {
        let dir = scratch("mesh");
        std::fs::write(dir.join("table.obj"), box_obj([1.0, 1.0, 0.04])).unwrap();
        let file = dir.join("shapes.json");
        std::fs::write(
            &file,
            r#"{"table": {"type": "mesh", "file": "table.obj"},
                "block": {"type": "box", "size": [0.05, 0.05, 0.05]}}"#,
        )
        .unwrap();
        let shapes = read_shapes_file(&file, &tracked()).unwrap();
        let table = &shapes["table"];
        assert!(table.hull().is_some());
        assert!((table.half_extents().z - 0.02).abs() < 1e-9);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_shapes_files_are_refused_naming_file_line_and_object() {
        let dir = scratch("bad");
        let file = dir.join("shapes.json");
        for (text, says) in [
            (
                "{\"table\":\n {\"type\": \"box\", \"size\": [1, 1]}}",
                "line 2",
            ),
            (
                r#"{"table": {"type": "box", "size": [1, 0, 1]}}"#,
                "`table`",
            ),
            (
                r#"{"shelf": {"type": "sphere", "radius": 0.1}}"#,
                "`shelf`, which no frame tracks (tracked: block, table)",
            ),
            (
                r#"{"table": {"type": "mesh", "file": "none.stl"}}"#,
                "none.stl",
            ),
        ] {
            std::fs::write(&file, text).unwrap();
            let e = read_shapes_file(&file, &tracked()).unwrap_err().to_string();
            assert!(e.contains("shapes.json") && e.contains(says), "{e}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
