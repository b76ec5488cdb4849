//! A library error's message in the words of its front end: the command line names options by
//! their flags, Python by its keywords and dict keys, and both number tendons as robot
//! files do (from 1).

use super::build::file_field;
use crate::Error;

/// Which front end shows a library message: each names the options the way it takes them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Front {
    /// The `tdcr` command: flags (`--motion 1=release`).
    CommandLine,
    /// The Python package: keywords and dict keys (`"motion": "release"`).
    Python,
}

/// The option a library hint names as something to change, written into the hint as
/// `` `tendons[I].KEY` `` (as the library writes it) and spelled for each front end by
/// [`user_message`].
const OPTIONS: [&str; 1] = ["motion"];

/// How `front` gives tendon `number`'s (from 1) option `key` ([`OPTIONS`]).
fn spelled(front: Front, number: usize, key: &str) -> String {
    match (front, key) {
        (Front::CommandLine, "motion") => format!("`tdcr solve --motion {number}=pull` or `{number}=release`"),
        (Front::Python, "motion") => {
            format!("`tdcr.solve` with `\"motion\": \"pull\"` or `\"release\"` in tendon {number}'s dict")
        }
        _ => format!("`{}`", file_field(&format!("tendons[{}].{key}", number - 1), false)),
    }
}

/// `hint` with every option token (`` `tendons[I].KEY` `` for a key of [`OPTIONS`]) spelled for `front`.
fn spell_options(hint: &str, front: Front) -> String {
    let mut out = String::with_capacity(hint.len());
    let mut rest = hint;
    while let Some(at) = rest.find("`tendons[") {
        out.push_str(&rest[..at]);
        let tail = &rest[at + "`tendons[".len()..];
        let token = tail.find(']').and_then(|close| {
            let i: usize = tail[..close].parse().ok()?;
            let after = tail[close + 1..].strip_prefix('.')?;
            let key = OPTIONS
                .iter()
                .find(|k| after.strip_prefix(**k).is_some_and(|end| end.starts_with('`')))?;
            Some((i, *key, close + 2 + key.len() + 1))
        });
        match token {
            Some((i, key, used)) => {
                out.push_str(&spelled(front, i + 1, key));
                rest = &tail[used..];
            }
            None => {
                out.push_str("`tendons[");
                rest = tail;
            }
        }
    }
    out.push_str(rest);
    out
}

/// A library error's message in the words of `front`: an invalid input's or a model
/// limit's field path numbered as in robot files (`tendon[1].stiffness` for the library's
/// `tendons[0].stiffness`), and the options its hint names spelled as `front` takes them
/// (`--motion 1=release` on the command line); other errors as the library words them.
pub fn user_message(e: &Error, front: Front) -> String {
    match e {
        Error::InvalidInput { field, problem, hint } => format!(
            "invalid input: `{}` {problem}; {}",
            file_field(field, false),
            spell_options(hint, front)
        ),
        Error::ModelLimit { field, problem, hint } => format!(
            "outside the model: `{}` {problem}; {}",
            file_field(field, false),
            spell_options(hint, front)
        ),
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hint_names_the_motion_as_its_reader_gives_it() {
        let e = crate::error::limit(
            "tendons[0].friction",
            "is beyond the model",
            format!(
                "a full-slip solve ({}) gives the step",
                crate::error::option_token(0, "motion")
            ),
        );
        let cli = user_message(&e, Front::CommandLine);
        assert!(cli.starts_with("outside the model: `tendon[1].friction`"), "{cli}");
        assert!(
            cli.contains("(`tdcr solve --motion 1=pull` or `1=release`) gives"),
            "{cli}"
        );
        let python = user_message(&e, Front::Python);
        assert!(
            python.contains("`\"motion\": \"pull\"` or `\"release\"` in tendon 1's dict) gives"),
            "{python}"
        );
        // Another field in backquotes is left as it is.
        let other = crate::error::invalid("rod.length", "is -1", "see `tendons[0].stiffness` and `tendons[2]");
        assert!(user_message(&other, Front::Python).ends_with("see `tendons[0].stiffness` and `tendons[2]"));
    }
}
