//! The learner's question, the teacher's answer sources, and the suggestion (thesis §3.3.1.2).

use std::io::{Read, Write};

use k::nalgebra::Vector3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use thiserror::Error;

use crate::demo::Answer;

/// The query posed on every 0→1 switch of the detector.
pub const QUERY: &str = "Do I have to move in a straight line there?";

/// The suggestion shown after "no" or "I don't know".
pub const SUGGESTION: &str = "Please do not move in a line unless the robot must move in a line.";

/// A query grounded in the scene: where the detected line is and what is near it.
#[derive(Debug, Clone, PartialEq)]
pub struct Question {
    /// Demonstration time of the query (s).
    pub t: f64,
    /// Frame of the query.
    pub frame: usize,
    /// Where the detected line starts (world, m).
    pub line_start: Vector3<f64>,
    /// Where the hand is now.
    pub line_end: Vector3<f64>,
    /// Objects nearest the line, with their distance to it (m), nearest first (at most 3).
    pub nearest_objects: Vec<(String, f64)>,
}

impl Question {
    /// Unit direction of the detected line (zero if it has no length).
    pub fn direction(&self) -> Vector3<f64> {
        (self.line_end - self.line_start)
            .try_normalize(1e-12)
            .unwrap_or_else(Vector3::zeros)
    }

    /// Length of the detected line so far (m).
    pub fn length(&self) -> f64 {
        (self.line_end - self.line_start).norm()
    }

    /// The question in words, physically grounded, with what each answer will do.
    pub fn describe(&self) -> String {
        let d = self.direction();
        let near = if self.nearest_objects.is_empty() {
            "no objects nearby".to_string()
        } else {
            self.nearest_objects
                .iter()
                .map(|(n, dist)| format!("{n} ({:.0} cm)", dist * 100.0))
                .collect::<Vec<_>>()
                .join(", ")
        };
        format!(
            "At t = {:.1} s you moved in a straight line: from ({:.2}, {:.2}, {:.2}) m, {:.0} cm so far, \
             heading ({:+.2}, {:+.2}, {:+.2}); nearest: {near}.\n{QUERY}\n  \
             [y] yes: the robot will keep this straight line in the task\n  \
             [n] no: the robot will move freely here\n  \
             [?] I don't know: the robot keeps the line to be safe",
            self.t,
            self.line_start.x,
            self.line_start.y,
            self.line_start.z,
            self.length() * 100.0,
            d.x,
            d.y,
            d.z
        )
    }
}

/// A question an answer list was asked, as its errors list it.
#[derive(Debug, Clone, PartialEq)]
pub struct Asked {
    /// Demonstration time of the question (s).
    pub t: f64,
    /// Where the hand was (world, m).
    pub position: Vector3<f64>,
    /// The answer the list gave, if it had one.
    pub answer: Option<Answer>,
}

/// The questions an answer list was asked, one line each: time, position and answer.
fn list_questions(asked: &[Asked]) -> String {
    if asked.is_empty() {
        return "no question was asked".into();
    }
    let lines: Vec<String> = asked
        .iter()
        .enumerate()
        .map(|(i, q)| {
            let answer = q.answer.map_or("no answer", answer_word);
            format!(
                "  question {} at t = {:.2} s, hand at ({:.2}, {:.2}, {:.2}) m: {answer}",
                i + 1,
                q.t,
                q.position.x,
                q.position.y,
                q.position.z
            )
        })
        .collect();
    format!("the questions:\n{}", lines.join("\n"))
}

/// The word `--answers` takes for an answer.
fn answer_word(answer: Answer) -> &'static str {
    match answer {
        Answer::Yes => "yes",
        Answer::No => "no",
        Answer::Unknown => "unknown",
    }
}

/// Why an answer could not be had.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum DialogueError {
    /// A question had no answer in the list: the list is too short, or (keyed by time) has
    /// none near the question's time. Later questions depend on this answer, so they are not
    /// known yet.
    #[error(
        "question {} at t = {:.2} s has no answer in --answers ({}); {}",
        asked.len(),
        asked.last().map_or(0.0, |q| q.t),
        given,
        list_questions(asked)
    )]
    Unanswered {
        /// The questions asked so far, the unanswered one last.
        asked: Vec<Asked>,
        /// What the list holds, as given.
        given: String,
    },
    /// A list held answers no question took.
    #[error(
        "--answers gives {} answers but {} questions were asked (unused: {}); {}",
        asked.len() + unused.len(),
        asked.len(),
        unused.join(", "),
        list_questions(asked)
    )]
    UnusedAnswers {
        /// The questions asked, with their answers.
        asked: Vec<Asked>,
        /// The answers no question took, as given.
        unused: Vec<String>,
    },
    /// The terminal could not be used.
    #[error("cannot ask on the terminal: {0}")]
    Terminal(String),
    /// An answer list did not parse.
    #[error("{0}")]
    Parse(String),
}

/// Something that answers the learner's queries.
pub trait AnswerSource {
    /// The answer to `question`.
    fn answer(&mut self, question: &Question) -> Result<Answer, DialogueError>;

    /// Shows the learner's suggestion ([`SUGGESTION`]) after a "no" or "I don't know". A person
    /// sees it; sources that only answer ignore it.
    fn suggest(&mut self, _suggestion: &str) -> Result<(), DialogueError> {
        Ok(())
    }

    /// Tells a source that knows the teacher's mind (the simulated teacher's [`Oracle`]) what
    /// the teacher intended in the frames recorded since the last call: per frame, whether a
    /// required line was under way. Other sources ignore it.
    fn intend(&mut self, _required: &[bool]) {}

    /// The session ended: a source given its answers in advance ([`ListedAnswers`]) says if
    /// some were never asked for, so that answers meant for other questions never go unnoticed.
    fn finish(&self) -> Result<(), DialogueError> {
        Ok(())
    }
}

/// Parses one answer word: `yes`/`y`, `no`/`n`, `unknown`/`u`/`?`/`dont-know`.
pub(crate) fn parse_answer(word: &str) -> Option<Answer> {
    match word.trim().to_ascii_lowercase().as_str() {
        "yes" | "y" => Some(Answer::Yes),
        "no" | "n" => Some(Answer::No),
        "unknown" | "u" | "?" | "dont-know" | "idk" => Some(Answer::Unknown),
        _ => None,
    }
}

/// How far (s) a question's time may be from the time an answer is keyed by and still take it:
/// half a second. The detector asks about a line within a fraction of a second of when the
/// hand has made enough of it, so a list written from one run's questions (which `akl teach`
/// prints and records) fits a replay of the same recording, while questions a second apart
/// are not confused.
pub const ANSWER_TIME_TOLERANCE: f64 = 0.5;

/// Answers given in advance (`--answers`): in order (`yes,no,unknown`), or keyed by the time of
/// the question each answers (`9.9:yes,19.0:no`, each taken by the question nearest its time
/// within [`ANSWER_TIME_TOLERANCE`]). Every question must find an answer and every answer a
/// question ([`AnswerSource::finish`]); the errors list the questions asked with their times
/// and positions.
#[derive(Debug, Clone)]
pub struct ListedAnswers {
    /// Each answer with its time key (all keyed or none) and whether a question took it.
    answers: Vec<(Option<f64>, Answer, bool)>,
    given: String,
    asked: Vec<Asked>,
}

impl ListedAnswers {
    /// Parses a comma-separated list of answers, all of them plain or all keyed by time
    /// (`TIME:ANSWER`); the error names the bad item.
    pub fn parse(list: &str) -> Result<Self, DialogueError> {
        let parse_item = |item: &str| -> Result<(Option<f64>, Answer), DialogueError> {
            let (time, word) = match item.split_once(':') {
                Some((time, word)) => {
                    let t = time
                        .trim()
                        .parse::<f64>()
                        .ok()
                        .filter(|t| t.is_finite() && *t >= 0.0)
                        .ok_or_else(|| {
                            DialogueError::Parse(format!(
                                "`{}`: `{}` is not a time in seconds",
                                item.trim(),
                                time.trim()
                            ))
                        })?;
                    (Some(t), word)
                }
                None => (None, item),
            };
            let answer = parse_answer(word).ok_or_else(|| {
                DialogueError::Parse(format!(
                    "`{}` is not an answer (use yes, no or unknown, or TIME:ANSWER)",
                    word.trim()
                ))
            })?;
            Ok((time, answer))
        };
        let answers = list
            .split(',')
            .filter(|w| !w.trim().is_empty())
            .map(parse_item)
            .collect::<Result<Vec<_>, _>>()?;
        let keyed = answers.iter().filter(|(t, _)| t.is_some()).count();
        if keyed != 0 && keyed != answers.len() {
            return Err(DialogueError::Parse(
                "key every answer by time (9.9:yes,19.0:no) or none (yes,no)".into(),
            ));
        }
        Ok(ListedAnswers {
            answers: answers.into_iter().map(|(t, a)| (t, a, false)).collect(),
            given: list.trim().to_string(),
            asked: Vec::new(),
        })
    }

    /// Answers keyed by the times of the questions they answer (such as a recording's, which
    /// `given` names in errors).
    pub fn keyed(answers: &[(f64, Answer)], given: &str) -> Self {
        ListedAnswers {
            answers: answers.iter().map(|(t, a)| (Some(*t), *a, false)).collect(),
            given: given.to_string(),
            asked: Vec::new(),
        }
    }

    /// The questions asked so far, with the answers they took.
    pub fn asked(&self) -> &[Asked] {
        &self.asked
    }

    /// The answer `question` takes: the next in order, or the nearest unused one in time.
    fn take(&mut self, question: &Question) -> Option<Answer> {
        let index = if self.answers.first().is_some_and(|(t, _, _)| t.is_some()) {
            self.answers
                .iter()
                .enumerate()
                .filter(|(_, (_, _, used))| !used)
                .filter_map(|(i, (t, _, _))| t.map(|t| (i, (t - question.t).abs())))
                .filter(|(_, gap)| *gap <= ANSWER_TIME_TOLERANCE)
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(i, _)| i)
        } else {
            self.answers.iter().position(|(_, _, used)| !used)
        }?;
        self.answers[index].2 = true;
        Some(self.answers[index].1)
    }
}

impl AnswerSource for ListedAnswers {
    fn answer(&mut self, question: &Question) -> Result<Answer, DialogueError> {
        let answer = self.take(question);
        self.asked.push(Asked {
            t: question.t,
            position: question.line_end,
            answer,
        });
        answer.ok_or_else(|| DialogueError::Unanswered {
            asked: self.asked.clone(),
            given: if self.given.is_empty() {
                "empty".into()
            } else {
                format!("`{}`", self.given)
            },
        })
    }

    fn finish(&self) -> Result<(), DialogueError> {
        let unused: Vec<String> = self
            .answers
            .iter()
            .filter(|(_, _, used)| !used)
            .map(|(t, a, _)| match t {
                Some(t) => format!("{t}:{}", answer_word(*a)),
                None => answer_word(*a).to_string(),
            })
            .collect();
        if unused.is_empty() {
            return Ok(());
        }
        Err(DialogueError::UnusedAnswers {
            asked: self.asked.clone(),
            unused,
        })
    }
}

/// Says yes to everything (keeps every detected line).
#[derive(Debug, Clone, Copy, Default)]
pub struct AllYes;

impl AnswerSource for AllYes {
    fn answer(&mut self, _: &Question) -> Result<Answer, DialogueError> {
        Ok(Answer::Yes)
    }
}

/// A simulated teacher who knows which lines the task requires and errs at given rates.
#[derive(Debug, Clone)]
pub struct Oracle {
    required: Vec<bool>,
    window: usize,
    wrong_rate: f64,
    unknown_rate: f64,
    rng: ChaCha8Rng,
}

impl Oracle {
    /// An oracle over per-frame flags "a required line is under way" (more can follow through
    /// [`AnswerSource::intend`] as a teacher records them), answering yes when one was under
    /// way within the last `window` frames; wrong with `wrong_rate`, "I don't know" with
    /// `unknown_rate`.
    pub fn new(
        required: Vec<bool>,
        window: usize,
        wrong_rate: f64,
        unknown_rate: f64,
        rng: ChaCha8Rng,
    ) -> Self {
        Oracle {
            required,
            window,
            wrong_rate,
            unknown_rate,
            rng,
        }
    }
}

impl AnswerSource for Oracle {
    fn answer(&mut self, question: &Question) -> Result<Answer, DialogueError> {
        let end = question.frame.min(self.required.len().saturating_sub(1));
        let from = end.saturating_sub(self.window);
        let required = self
            .required
            .get(from..=end)
            .is_some_and(|s| s.iter().any(|x| *x));
        if self.rng.gen_bool(self.unknown_rate) {
            return Ok(Answer::Unknown);
        }
        let wrong = self.rng.gen_bool(self.wrong_rate);
        Ok(if required != wrong {
            Answer::Yes
        } else {
            Answer::No
        })
    }

    fn intend(&mut self, required: &[bool]) {
        self.required.extend_from_slice(required);
    }
}

/// Asks a person: prints the grounded question and takes one key per answer (y, n or ?).
///
/// Whitespace (such as an Enter pressed out of habit) is ignored and any other key asks again,
/// so a stray keystroke never becomes an answer. The caller decides whether the terminal
/// delivers keys at once (raw mode) or a line at a time.
pub struct Terminal<R, W> {
    input: R,
    output: W,
}

impl<R: Read, W: Write> Terminal<R, W> {
    /// Asks on `output` and reads answers from `input` (normally `/dev/tty`, so a demonstration
    /// can stream in on stdin at the same time).
    pub fn new(input: R, output: W) -> Self {
        Terminal { input, output }
    }

    fn prompt(&mut self) -> std::io::Result<()> {
        write!(self.output, "answer [y/n/?]: ")?;
        self.output.flush()
    }
}

/// The answer one key stands for.
fn answer_for_key(key: u8) -> Option<Answer> {
    match key.to_ascii_lowercase() {
        b'y' => Some(Answer::Yes),
        b'n' => Some(Answer::No),
        b'?' | b'u' => Some(Answer::Unknown),
        _ => None,
    }
}

impl<R: Read, W: Write> AnswerSource for Terminal<R, W> {
    fn answer(&mut self, question: &Question) -> Result<Answer, DialogueError> {
        let io = |e: std::io::Error| DialogueError::Terminal(e.to_string());
        writeln!(self.output, "\n{}", question.describe()).map_err(io)?;
        self.prompt().map_err(io)?;
        let mut key = [0u8; 1];
        loop {
            if self.input.read(&mut key).map_err(io)? == 0 {
                return Err(DialogueError::Terminal(
                    "the terminal closed before an answer".into(),
                ));
            }
            if key[0].is_ascii_whitespace() {
                continue;
            }
            if let Some(answer) = answer_for_key(key[0]) {
                writeln!(self.output, "{}", key[0] as char).map_err(io)?;
                return Ok(answer);
            }
            writeln!(self.output).map_err(io)?;
            self.prompt().map_err(io)?;
        }
    }

    fn suggest(&mut self, suggestion: &str) -> Result<(), DialogueError> {
        let io = |e: std::io::Error| DialogueError::Terminal(e.to_string());
        writeln!(self.output, "{suggestion}").map_err(io)?;
        self.output.flush().map_err(io)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn question(frame: usize) -> Question {
        Question {
            t: 1.0,
            frame,
            line_start: Vector3::new(0.5, 0.2, 0.3),
            line_end: Vector3::new(0.5, 0.0, 0.3),
            nearest_objects: vec![("scanner_1".into(), 0.12)],
        }
    }

    fn at(t: f64) -> Question {
        Question { t, ..question(1) }
    }

    #[test]
    fn listed_answers_run_out_with_a_clear_error() {
        let mut list = ListedAnswers::parse("yes, n").unwrap();
        assert_eq!(list.answer(&at(1.0)), Ok(Answer::Yes));
        assert_eq!(list.answer(&at(2.0)), Ok(Answer::No));
        assert_eq!(list.finish(), Ok(()));
        let err = list.answer(&at(3.5)).unwrap_err().to_string();
        assert!(
            err.contains("question 3 at t = 3.50 s has no answer")
                && err.contains("question 1 at t = 1.00 s, hand at (0.50, 0.00, 0.30) m: yes")
                && err.contains("question 2 at t = 2.00 s")
                && err.contains("`yes, n`"),
            "{err}"
        );
        assert!(ListedAnswers::parse("yes,maybe")
            .unwrap_err()
            .to_string()
            .contains("`maybe`"));
    }

    #[test]
    fn answers_left_over_are_an_error_naming_the_questions() {
        let mut list = ListedAnswers::parse("yes,no").unwrap();
        assert_eq!(list.answer(&at(9.9)), Ok(Answer::Yes));
        let err = list.finish().unwrap_err().to_string();
        assert!(
            err.contains("gives 2 answers but 1 questions")
                && err.contains("unused: no")
                && err.contains("question 1 at t = 9.90 s"),
            "{err}"
        );
    }

    #[test]
    fn answers_keyed_by_time_go_to_the_question_nearest_their_time() {
        let mut list = ListedAnswers::parse("19.0:no, 9.9:yes").unwrap();
        assert_eq!(list.answer(&at(10.1)), Ok(Answer::Yes));
        assert_eq!(list.answer(&at(18.8)), Ok(Answer::No));
        assert_eq!(list.finish(), Ok(()));
        // A question with no answer near it is refused, naming it, and so is an answer left.
        let mut list = ListedAnswers::parse("9.9:yes,19.0:no").unwrap();
        let err = list.answer(&at(14.0)).unwrap_err().to_string();
        assert!(
            err.contains("question 1 at t = 14.00 s has no answer"),
            "{err}"
        );
        let err = list.finish().unwrap_err().to_string();
        assert!(err.contains("unused: 9.9:yes, 19:no"), "{err}");
        for bad in ["9.9:yes,no", "x:yes", "-1:yes"] {
            assert!(
                matches!(ListedAnswers::parse(bad), Err(DialogueError::Parse(_))),
                "{bad}"
            );
        }
    }

    #[test]
    fn a_perfect_oracle_knows_required_lines() {
        let mut required = vec![false; 100];
        required[40..60].iter_mut().for_each(|x| *x = true);
        let mut oracle = Oracle::new(required, 10, 0.0, 0.0, ChaCha8Rng::seed_from_u64(1));
        assert_eq!(oracle.answer(&question(55)), Ok(Answer::Yes));
        assert_eq!(oracle.answer(&question(65)), Ok(Answer::Yes));
        assert_eq!(oracle.answer(&question(90)), Ok(Answer::No));
        let mut liar = Oracle::new(vec![true; 10], 0, 1.0, 0.0, ChaCha8Rng::seed_from_u64(1));
        assert_eq!(liar.answer(&question(5)), Ok(Answer::No));
    }

    #[test]
    fn the_terminal_shows_a_grounded_question_and_takes_one_key() {
        let mut out = Vec::new();
        let mut terminal = Terminal::new(&b"x\n?\n"[..], &mut out);
        assert_eq!(terminal.answer(&question(3)), Ok(Answer::Unknown));
        let shown = String::from_utf8(out).unwrap();
        assert!(
            shown.contains(QUERY) && shown.contains("20 cm") && shown.contains("scanner_1 (12 cm)"),
            "{shown}"
        );
        assert!(shown.contains("(+0.00, -1.00, +0.00)"), "{shown}");
        assert_eq!(shown.matches("answer [y/n/?]").count(), 2, "{shown}");
        assert!(!shown.contains(SUGGESTION));
        let mut out = Vec::new();
        Terminal::new(&b""[..], &mut out)
            .suggest(SUGGESTION)
            .unwrap();
        assert_eq!(String::from_utf8(out).unwrap(), format!("{SUGGESTION}\n"));
    }

    #[test]
    fn an_oracle_learns_the_intent_as_it_is_recorded() {
        let mut oracle = Oracle::new(Vec::new(), 0, 0.0, 0.0, ChaCha8Rng::seed_from_u64(1));
        oracle.intend(&[false, false]);
        oracle.intend(&[true]);
        assert_eq!(oracle.answer(&question(2)), Ok(Answer::Yes));
        assert_eq!(oracle.answer(&question(1)), Ok(Answer::No));
    }
}
