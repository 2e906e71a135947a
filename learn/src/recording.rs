//! Demonstration files: recording one as it happens, and reading one back whatever its format.
//!
//! A recording is written to `<path>.partial` and renamed to `<path>` only when it is
//! complete, so `<path>` is never half-written. If the process is killed, the `.partial` file
//! stays behind with everything but its last second, and [`read_demo_file`] recovers it.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use crate::demo::{Demo, DemoHeader, DialogueEvent};
use crate::demo_error::DemoError;
use crate::jsonl::{read_jsonl, JsonlDemoWriter};
use crate::mcap_io::{read_mcap, McapDemoWriter, Truncation, MCAP_MAGIC};
use crate::session::RecordingSink;
use crate::shapes::prepare_shapes;

/// The two demonstration formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DemoFormat {
    /// One JSON object per line (any robot driver can write it).
    Jsonl,
    /// MCAP with Foxglove schemas (what `akl teach` records; opens in Foxglove).
    Mcap,
}

impl DemoFormat {
    /// The format a file name asks for: `.mcap` or `.jsonl`; `None` for anything else.
    pub fn for_path(path: &Path) -> Option<DemoFormat> {
        match path.extension().and_then(|e| e.to_str()) {
            Some("mcap") => Some(DemoFormat::Mcap),
            Some("jsonl") => Some(DemoFormat::Jsonl),
            _ => None,
        }
    }
}

/// Why a demonstration file could not be read or written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DemoFileError {
    /// The file could not be opened, read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The file's contents are not a valid demonstration.
    #[error("{path}: {source}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong, with the line or frame.
        source: DemoError,
    },
    /// The file name does not say which format to write.
    #[error("{path}: a recording must be named .mcap or .jsonl")]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
}

/// A demonstration read from a file.
#[derive(Debug, Clone)]
pub struct LoadedDemo {
    /// The demonstration.
    pub demo: Demo,
    /// What a truncated MCAP recording lost, if it was truncated.
    pub truncation: Option<Truncation>,
    /// The format it was in.
    pub format: DemoFormat,
}

/// Reads a JSONL or MCAP demonstration (told apart by content, so `.partial` files of killed
/// recordings read too), with the mesh files of the shapes its header declares (relative to
/// its folder); errors name the file and the line or frame.
pub fn read_demo_file(path: &Path) -> Result<LoadedDemo, DemoFileError> {
    let bytes = std::fs::read(path).map_err(|source| DemoFileError::Io {
        path: path.into(),
        source,
    })?;
    let invalid = |source| DemoFileError::Invalid {
        path: path.into(),
        source,
    };
    let mut loaded = if bytes.starts_with(MCAP_MAGIC) {
        let (demo, truncation) = read_mcap(&bytes).map_err(invalid)?;
        LoadedDemo {
            demo,
            truncation,
            format: DemoFormat::Mcap,
        }
    } else {
        let text = String::from_utf8(bytes)
            .map_err(|_| invalid(DemoError::Format("neither MCAP nor UTF-8 JSONL".into())))?;
        LoadedDemo {
            demo: read_jsonl(&text).map_err(invalid)?,
            truncation: None,
            format: DemoFormat::Jsonl,
        }
    };
    let demo = &mut loaded.demo;
    let tracked: Vec<String> = demo.objects.iter().map(|o| o.name.clone()).collect();
    let folder = path.parent().unwrap_or(Path::new(""));
    prepare_shapes(&mut demo.header.shapes, folder, &tracked).map_err(|e| {
        invalid(match loaded.format {
            DemoFormat::Jsonl => DemoError::Line {
                line: 1,
                message: e.to_string(),
            },
            DemoFormat::Mcap => DemoError::Format(format!("the header: {e}")),
        })
    })?;
    Ok(loaded)
}

enum Writer {
    Mcap(Box<McapDemoWriter<BufWriter<File>>>),
    Jsonl(JsonlDemoWriter<BufWriter<File>>),
}

/// A demonstration being recorded into a file, streamed as it happens.
pub struct Recording {
    path: PathBuf,
    partial: PathBuf,
    writer: Writer,
}

impl Recording {
    /// Starts recording `header` and the named objects into `path` (`.mcap` or `.jsonl`),
    /// writing to `<path>.partial` until [`Recording::finish`]; missing folders are created.
    pub fn create(
        path: &Path,
        header: &DemoHeader,
        objects: &[String],
    ) -> Result<Recording, DemoFileError> {
        let format = DemoFormat::for_path(path)
            .ok_or_else(|| DemoFileError::UnknownFormat { path: path.into() })?;
        let partial = partial_path(path);
        let io = |source| DemoFileError::Io {
            path: partial.clone(),
            source,
        };
        if let Some(dir) = partial.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(io)?;
        }
        let file = BufWriter::new(File::create(&partial).map_err(io)?);
        let writer = match format {
            DemoFormat::Mcap => Writer::Mcap(Box::new(
                McapDemoWriter::new(file, header, objects).map_err(io)?,
            )),
            DemoFormat::Jsonl => Writer::Jsonl(JsonlDemoWriter::new(file, header).map_err(io)?),
        };
        Ok(Recording {
            path: path.into(),
            partial,
            writer,
        })
    }

    /// Where the recording is written until it is finished.
    pub fn partial_path(&self) -> &Path {
        &self.partial
    }

    /// Completes the file, makes it durable and moves it to its name; returns that name.
    pub fn finish(self) -> Result<PathBuf, DemoFileError> {
        let io = |source| DemoFileError::Io {
            path: self.partial.clone(),
            source,
        };
        let buffered = match self.writer {
            Writer::Mcap(w) => w.finish(),
            Writer::Jsonl(w) => w.finish(),
        }
        .map_err(io)?;
        let file = buffered.into_inner().map_err(|e| io(e.into_error()))?;
        file.sync_all().map_err(io)?;
        std::fs::rename(&self.partial, &self.path).map_err(io)?;
        Ok(self.path)
    }
}

impl RecordingSink for Recording {
    fn frame(&mut self, demo: &Demo, index: usize) -> std::io::Result<()> {
        match &mut self.writer {
            Writer::Mcap(w) => w.write_frame(demo, index),
            Writer::Jsonl(w) => w.write_frame(demo, index),
        }
    }

    fn event(&mut self, event: &DialogueEvent) -> std::io::Result<()> {
        match &mut self.writer {
            Writer::Mcap(w) => w.write_event(event),
            Writer::Jsonl(w) => w.write_event(event),
        }
    }
}

/// `<path>.partial`.
pub(crate) fn partial_path(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_os_string();
    name.push(".partial");
    PathBuf::from(name)
}

/// Writes a whole demonstration to `path` in the format its name asks for, atomically (the
/// tests' round trips).
#[cfg(test)]
pub(crate) fn write_demo_file(path: &Path, demo: &Demo) -> Result<PathBuf, DemoFileError> {
    let names: Vec<String> = demo.objects.iter().map(|o| o.name.clone()).collect();
    let mut recording = Recording::create(path, &demo.header, &names)?;
    let partial = recording.partial_path().to_path_buf();
    let io = |source| DemoFileError::Io {
        path: partial.clone(),
        source,
    };
    crate::session::write_demo(&mut recording, demo).map_err(io)?;
    recording.finish()
}

impl std::fmt::Debug for Recording {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Recording")
            .field("path", &self.path)
            .field("partial", &self.partial)
            .finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::okl::synth::DemoBuilder;

    fn demo() -> Demo {
        DemoBuilder::new("t", [0.3, 0.0, 0.4], 100.0, 0.0005, 1)
            .object("part", [0.4, 0.1, 0.2])
            .curve([0.4, 0.1, 0.25], 0.2)
            .grasp("part")
            .mark()
            .line([0.4, -0.2, 0.25], 0.2, Some(crate::demo::Answer::Yes))
            .build()
    }

    #[test]
    fn both_formats_round_trip_through_files_and_leave_no_partial() {
        let dir = std::env::temp_dir().join(format!("akl-recording-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let demo = demo();
        for (name, format) in [("d.mcap", DemoFormat::Mcap), ("d.jsonl", DemoFormat::Jsonl)] {
            let path = dir.join(name);
            assert_eq!(write_demo_file(&path, &demo).unwrap(), path);
            assert!(!partial_path(&path).exists());
            let loaded = read_demo_file(&path).unwrap();
            assert_eq!(loaded.format, format);
            assert!(loaded.truncation.is_none());
            assert_eq!(loaded.demo.len(), demo.len());
            assert_eq!(loaded.demo.events.len(), demo.events.len());
            assert_eq!(loaded.demo.detector, demo.detector);
        }
        let bad = dir.join("d.txt");
        assert!(matches!(
            write_demo_file(&bad, &demo),
            Err(DemoFileError::UnknownFormat { .. })
        ));
        std::fs::write(
            &bad,
            b"{\"akl_demo\": 1, \"task\": \"t\", \"frame\": \"world\"}\n{\"t\": 0}\n",
        )
        .unwrap();
        let e = read_demo_file(&bad).unwrap_err().to_string();
        assert!(e.contains("d.txt") && e.contains("line 2"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
