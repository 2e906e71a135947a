//! Who answers the learner's questions, from the `--answers` option.

use std::fs::{File, OpenOptions};

use akl_learn::dialogue::{AllYes, AnswerSource, ListedAnswers, Terminal};
use akl_learn::teach::oracle;
use akl_learn::teacher::TeacherProfile;

use crate::exit::CliError;
use crate::tty::KeyReader;

/// The terminal the questions are asked on: the controlling terminal, so that a demonstration
/// can stream in on standard input at the same time.
const TTY: &str = "/dev/tty";

/// The answer source `spec` names: `oracle` (needs the simulated teacher's profile and seed),
/// `all-yes`, `terminal`, or a comma-separated list of yes / no / unknown.
pub(crate) fn answer_source(
    spec: &str,
    simulated: Option<(&TeacherProfile, u64)>,
) -> Result<Box<dyn AnswerSource>, CliError> {
    match spec {
        "oracle" => {
            let (profile, seed) = simulated.ok_or_else(|| {
                CliError::input(
                    "--answers oracle needs the simulated teacher (--teacher sim): only it knows the task's true lines",
                )
            })?;
            Ok(Box::new(oracle(profile, seed)))
        }
        "all-yes" => Ok(Box::new(AllYes)),
        "terminal" => {
            let open = |e: std::io::Error| {
                CliError::input(format!(
                    "cannot open the terminal {TTY} to ask questions ({e}); pass --answers with a list or all-yes"
                ))
            };
            let input = File::open(TTY).map_err(open)?;
            let output = OpenOptions::new().write(true).open(TTY).map_err(open)?;
            Ok(Box::new(Terminal::new(KeyReader::new(input), output)))
        }
        list => Ok(Box::new(ListedAnswers::parse(list).map_err(|e| {
            CliError::input(format!(
                "--answers: {e} (or use oracle, all-yes or terminal)"
            ))
        })?)),
    }
}
