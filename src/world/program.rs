//! Built-in robot programs: an action name such as `"goto L2; measure"` read as [`Step`]s
//! against a [`Map`] (see `docs/plans.md`, "Simulated robots").

use super::map::Map;

/// One step of a built-in robot action (see `docs/plans.md`, "Simulated robots").
#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    /// `goto LOC`: leave the current location, drive along the topological map to the back of
    /// `LOC`'s queue.
    Goto(usize),
    /// `measure [SECONDS]`: stand still and measure; the outcome is one of the place's
    /// exponential outputs, drawn with probability ∝ its rate.
    Measure(Option<f64>),
    /// `wait [SECONDS]`: stand still; then like `measure`.
    Wait(Option<f64>),
    /// `decide`: wait until the robot is at the front of its location's queue, then let the
    /// net decide (policy or weights).
    Decide,
}

/// Why an action name is not a valid built-in robot program. `step` is the offending
/// `;`-separated part as written.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ProgramError {
    /// `goto` names a location the map does not have.
    #[error("`{step}`: location `{location}` does not exist")]
    UnknownLocation {
        /// The step, trimmed.
        step: String,
        /// The missing location.
        location: String,
    },
    /// `goto` without exactly one location.
    #[error("`{step}`: expected `goto LOCATION`")]
    GotoArity {
        /// The step, trimmed.
        step: String,
    },
    /// `measure`/`wait` with a duration that is not a number of seconds ≥ 0 and ≤ 10 years.
    #[error("`{step}`: `{value}` is not a number of seconds ≥ 0 and ≤ 315576000 (10 years)")]
    BadSeconds {
        /// The step, as written (untrimmed).
        step: String,
        /// The duration as written.
        value: String,
    },
    /// `measure`, `wait` or `decide` followed by too many words.
    #[error("`{step}`: too many words")]
    TooManyWords {
        /// The step, trimmed.
        step: String,
    },
    /// Built-in steps mixed with other words (a user action's name cannot contain them).
    #[error("`{action}` mixes built-in steps (goto, measure, wait, decide) with other words")]
    Mixed {
        /// The whole action name.
        action: String,
    },
}

impl Map {
    /// Reads an action name as a built-in robot program: steps separated by `;`, e.g.
    /// `"goto L2; measure"`. `Ok(None)`: not a built-in (a user action of that name).
    pub fn program(&self, action: &str) -> Result<Option<Vec<Step>>, ProgramError> {
        let mut steps = Vec::new();
        let mut user = false;
        for part in action.split(';') {
            let words: Vec<&str> = part.split_whitespace().collect();
            let step_name = || part.trim().to_string();
            let seconds = |w: Option<&&str>| -> Result<Option<f64>, ProgramError> {
                match w {
                    None => Ok(None),
                    Some(s) => match s.parse::<f64>() {
                        Ok(v) if crate::limits::valid_wait(v) => Ok(Some(v)),
                        _ => Err(ProgramError::BadSeconds {
                            step: part.to_string(),
                            value: s.to_string(),
                        }),
                    },
                }
            };
            let step = match words.as_slice() {
                ["goto", loc] => {
                    Step::Goto(
                        self.location(loc)
                            .ok_or_else(|| ProgramError::UnknownLocation {
                                step: step_name(),
                                location: loc.to_string(),
                            })?,
                    )
                }
                ["goto", ..] => return Err(ProgramError::GotoArity { step: step_name() }),
                ["measure", rest @ ..] if rest.len() <= 1 => Step::Measure(seconds(rest.first())?),
                ["wait", rest @ ..] if rest.len() <= 1 => Step::Wait(seconds(rest.first())?),
                ["decide"] => Step::Decide,
                ["measure" | "wait" | "decide", ..] => {
                    return Err(ProgramError::TooManyWords { step: step_name() });
                }
                _ => {
                    user = true;
                    continue;
                }
            };
            steps.push(step);
        }
        match (user, steps.is_empty()) {
            (true, true) => Ok(None),
            (true, false) => Err(ProgramError::Mixed {
                action: action.to_string(),
            }),
            (false, _) => Ok(Some(steps)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::map::Location;

    fn map() -> Map {
        let at = |n: &str| Location {
            name: n.to_string(),
            x: 0.0,
            y: 0.0,
            queue_dir: [0.0, -1.0],
            places: vec![],
        };
        Map {
            edges: vec![(0, 1)],
            ..Map::bare(vec![at("A"), at("B")])
        }
    }

    #[test]
    fn built_in_programs_are_read_step_by_step() {
        let m = map();
        assert_eq!(
            m.program(" goto B ;measure 2.5; wait; decide"),
            Ok(Some(vec![
                Step::Goto(1),
                Step::Measure(Some(2.5)),
                Step::Wait(None),
                Step::Decide
            ]))
        );
        assert_eq!(m.program("check_temperature"), Ok(None));
        assert_eq!(
            m.program("goto C"),
            Err(ProgramError::UnknownLocation {
                step: "goto C".into(),
                location: "C".into()
            })
        );
        assert_eq!(
            m.program("goto A B").unwrap_err().to_string(),
            "`goto A B`: expected `goto LOCATION`"
        );
        assert_eq!(
            m.program("wait -1").unwrap_err().to_string(),
            "`wait -1`: `-1` is not a number of seconds ≥ 0 and ≤ 315576000 (10 years)"
        );
        assert!(matches!(
            m.program("measure 1e300"),
            Err(ProgramError::BadSeconds { value, .. }) if value == "1e300"
        ));
        assert_eq!(
            m.program("wait 315576000").unwrap(),
            Some(vec![Step::Wait(Some(315576000.0))])
        );
        assert!(matches!(
            m.program("goto A; beep"),
            Err(ProgramError::Mixed { .. })
        ));
        assert_eq!(m.neighbours(0).collect::<Vec<_>>(), [1]);
        assert_eq!(m.location("B"), Some(1));
    }
}
