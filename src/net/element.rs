//! The parts a net is drawn from: [`Place`], [`Transition`] (with its [`Timing`] and
//! [`Servers`]), [`Arc`] (with its [`ArcKind`]) and canvas [`Position`]s.

use serde::{Deserialize, Serialize};

use super::{PlaceId, TransitionId};

/// A point on the drawing canvas, in the unit of the file it came from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Position {
    /// Horizontal coordinate.
    pub x: f64,
    /// Vertical coordinate (grows downwards, as in every editor we read).
    pub y: f64,
}

/// A place: a name, an initial marking and an optional capacity.
#[derive(Clone, Debug, PartialEq)]
pub struct Place {
    /// Name shown to users; unique in the net.
    pub name: String,
    /// Tokens in the initial marking.
    pub initial: u32,
    /// Most tokens the place may hold; `None` for unbounded.
    pub capacity: Option<u32>,
    /// Position on the canvas, when the file gave one.
    pub position: Option<Position>,
}

/// How many firings of an exponential transition run concurrently.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Servers {
    /// One server: the rate does not grow with the enabling degree.
    Single,
    /// As many servers as the enabling degree.
    Infinite,
    /// `k` servers (k ≥ 1).
    K(u32),
}

impl Servers {
    /// How many servers work when the enabling degree is `degree`.
    #[inline]
    pub fn active(self, degree: u32) -> u32 {
        match self {
            Servers::Single => degree.min(1),
            Servers::Infinite => degree,
            Servers::K(k) => degree.min(k),
        }
    }
}

/// Whether a transition fires at once (immediate) or after an exponential delay.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Timing {
    /// Fires in zero time; among enabled immediate transitions only those of the highest
    /// priority may fire, chosen with probability ∝ weight.
    Immediate {
        /// Relative weight (≥ 0; 0 = a decision left to the policy).
        weight: f64,
        /// Priority level (≥ 1).
        priority: u32,
    },
    /// Fires after an exponentially distributed delay.
    Exponential {
        /// Rate per server (> 0, finite).
        rate: f64,
        /// Server semantics.
        servers: Servers,
    },
}

/// A transition: a name and its timing.
#[derive(Clone, Debug, PartialEq)]
pub struct Transition {
    /// Name shown to users; unique in the net.
    pub name: String,
    /// Immediate or exponential, with its parameters.
    pub timing: Timing,
    /// Position on the canvas, when the file gave one.
    pub position: Option<Position>,
}

impl Transition {
    /// True for immediate transitions.
    #[inline]
    pub fn is_immediate(&self) -> bool {
        matches!(self.timing, Timing::Immediate { .. })
    }
}

/// What a rate and a weight must be: one rule, and one way of saying it, for
/// [`NetBuilder::build`](super::NetBuilder::build), the readers and the viewer's editor, so a
/// bad number reads the same wherever it was typed.
impl Timing {
    /// What a rate must be, as the error messages say it.
    pub(crate) const RATE_EXPECTED: &'static str = "must be a finite number > 0";
    /// What a weight must be, as the error messages say it.
    pub(crate) const WEIGHT_EXPECTED: &'static str = "must be a finite number ≥ 0";

    /// `v` as an exponential transition's rate, or what a rate must be.
    pub(crate) fn rate(v: f64) -> Result<f64, &'static str> {
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(Self::RATE_EXPECTED)
        }
    }

    /// `v` as an immediate transition's weight, or what a weight must be.
    pub(crate) fn weight(v: f64) -> Result<f64, &'static str> {
        if v.is_finite() && v >= 0.0 {
            Ok(v)
        } else {
            Err(Self::WEIGHT_EXPECTED)
        }
    }
}

/// What an arc does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum ArcKind {
    /// Place → transition: needs and consumes `weight` tokens.
    Input,
    /// Transition → place: produces `weight` tokens.
    Output,
    /// Place —o transition: the transition needs fewer than `weight` tokens.
    Inhibitor,
}

/// An arc between a place and a transition, as drawn in the file.
#[derive(Clone, Debug, PartialEq)]
pub struct Arc {
    /// Input, output or inhibitor.
    pub kind: ArcKind,
    /// The place end.
    pub place: PlaceId,
    /// The transition end.
    pub transition: TransitionId,
    /// Multiplicity (≥ 1).
    pub weight: u32,
    /// Bend points, in drawing order from source to target.
    pub points: Vec<Position>,
}
