//! A tendon: its routing, tension and where it ends.

use crate::model::routing::Routing;

/// One tendon, modelled as a frictionless Cosserat string (section 3 of the paper).
#[derive(Clone, Debug)]
pub struct Tendon {
    /// Path in the cross-section along s.
    pub routing: Routing,
    /// Tension tau_i (N), >= 0, constant along the tendon (frictionless).
    pub tension: f64,
    /// Arc length l_i where it is attached to the backbone (m), in (0, L]; `None` means
    /// the tip.
    pub termination: Option<f64>,
}

impl Tendon {
    /// A tendon along `routing` at `tension` (N), ending at the tip.
    pub fn new(routing: Routing, tension: f64) -> Self {
        Tendon {
            routing,
            tension,
            termination: None,
        }
    }

    /// The same tendon ending at arc length `s` (m).
    pub fn ending_at(mut self, s: f64) -> Self {
        self.termination = Some(s);
        self
    }

    /// The signed turns this tendon's path makes about the backbone from the base to its
    /// end, on a rod of `length` L (m): a helical routing of `turns` per rod length ending
    /// at l makes `turns * l / L`; 0 for a straight routing; `None` for a custom one.
    pub fn turns(&self, length: f64) -> Option<f64> {
        self.routing.turns_between(0.0, self.end(length), length)
    }

    /// Termination arc length on a rod of `length` L (m).
    pub fn end(&self, length: f64) -> f64 {
        self.termination.unwrap_or(length)
    }
}
