//! Per-frame rules every demonstration obeys, whatever its container.

/// Why a frame breaks the rules every demonstration obeys.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum FrameError {
    /// The frame's time is NaN or infinite.
    #[error("time {0} is not finite")]
    TimeNotFinite(f64),
    /// The frame is not later than the one before.
    #[error("time {t} s does not increase (previous frame at {previous} s)")]
    TimeNotIncreasing {
        /// This frame's time (s).
        t: f64,
        /// The previous frame's time (s).
        previous: f64,
    },
    /// An object of the earlier frames is missing.
    #[error("object `{0}` vanished (it was in earlier frames)")]
    Vanished(String),
    /// An object the first frame did not have appears.
    #[error("object `{0}` appeared mid-demo (it was not in the first frame)")]
    Appeared(String),
}

impl From<FrameError> for String {
    fn from(e: FrameError) -> String {
        e.to_string()
    }
}

/// Checks frames as they arrive: finite, strictly increasing times and the same set of objects
/// in every frame (an object that appears or vanishes mid-demo cannot be tracked or grounded).
#[derive(Debug, Default)]
pub(crate) struct FrameChecker {
    last_time: Option<f64>,
    objects: Option<Vec<String>>,
}

impl FrameChecker {
    /// The objects of the frames checked so far (empty before the first frame).
    pub(crate) fn objects(&self) -> &[String] {
        self.objects.as_deref().unwrap_or(&[])
    }

    /// Checks the next frame's time and object names; the message says what is wrong.
    pub(crate) fn check(&mut self, t: f64, objects: &[&str]) -> Result<(), FrameError> {
        if !t.is_finite() {
            return Err(FrameError::TimeNotFinite(t));
        }
        if let Some(previous) = self.last_time {
            if t <= previous {
                return Err(FrameError::TimeNotIncreasing { t, previous });
            }
        }
        self.last_time = Some(t);
        match &self.objects {
            None => self.objects = Some(objects.iter().map(|s| s.to_string()).collect()),
            Some(known) => {
                if let Some(gone) = known.iter().find(|k| !objects.contains(&k.as_str())) {
                    return Err(FrameError::Vanished(gone.clone()));
                }
                if let Some(new) = objects.iter().find(|o| !known.iter().any(|k| k == *o)) {
                    return Err(FrameError::Appeared(new.to_string()));
                }
            }
        }
        Ok(())
    }
}
