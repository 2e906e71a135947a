//! Per-frame rules every demonstration obeys, whatever its container.

/// Checks frames as they arrive: finite, strictly increasing times and the same set of objects
/// in every frame (an object that appears or vanishes mid-demo cannot be tracked or grounded).
#[derive(Debug, Default)]
pub struct FrameChecker {
    last_time: Option<f64>,
    objects: Option<Vec<String>>,
}

impl FrameChecker {
    /// The objects of the frames checked so far (empty before the first frame).
    pub fn objects(&self) -> &[String] {
        self.objects.as_deref().unwrap_or(&[])
    }

    /// Checks the next frame's time and object names; the message says what is wrong.
    pub fn check(&mut self, t: f64, objects: &[&str]) -> Result<(), String> {
        if !t.is_finite() {
            return Err(format!("time {t} is not finite"));
        }
        if let Some(last) = self.last_time {
            if t <= last {
                return Err(format!(
                    "time {t} s does not increase (previous frame at {last} s)"
                ));
            }
        }
        self.last_time = Some(t);
        match &self.objects {
            None => self.objects = Some(objects.iter().map(|s| s.to_string()).collect()),
            Some(known) => {
                if let Some(gone) = known.iter().find(|k| !objects.contains(&k.as_str())) {
                    return Err(format!(
                        "object `{gone}` vanished (it was in earlier frames)"
                    ));
                }
                if let Some(new) = objects.iter().find(|o| !known.iter().any(|k| k == *o)) {
                    return Err(format!(
                        "object `{new}` appeared mid-demo (it was not in the first frame)"
                    ));
                }
            }
        }
        Ok(())
    }
}
