//! A tendon: its routing, how it is actuated ([`Actuation`]: a tension or an actuator
//! pull-in), its axial stiffness, where it ends and its friction in the channels
//! ([`Friction`], docs/friction.md).

use crate::model::routing::Routing;

/// How a tendon is driven.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Actuation {
    /// By its tension tau_i (N), >= 0, constant along the tendon (frictionless): the paper's
    /// input.
    Tension(f64),
    /// By the pull-in q_i of its actuator: the tension is then an unknown of the solve, fixed
    /// by the length constraint of docs/actuation.md, and a tendon that would need to push
    /// goes slack (tau_i = 0).
    PullIn {
        /// Pull-in q_i (m; positive pulls the tendon in, negative lets it out), measured from
        /// the unloaded shape with the tendon just taut.
        displacement: f64,
        /// The tension (N) Newton starts from; `None` (or 0): the solver estimates it from a
        /// linear small-deflection model.
        start: Option<f64>,
    },
}

/// Which way a tendon with friction slides in its channels, which sets the sign of the
/// friction (docs/friction.md): full slip everywhere along the tendon.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Motion {
    /// The actuator pulls the tendon in: friction opposes the motion toward the base, so
    /// the tension falls from the base entry toward the termination (the default).
    Pull,
    /// The actuator lets the tendon out: friction opposes the motion toward the tip, so the
    /// tension rises from the base entry toward the termination.
    Release,
}

impl Motion {
    /// The sign w of the tension's rate tau_i' = w mu_i tau_i kappa_i: -1 pulling, +1
    /// releasing.
    pub fn sign(self) -> f64 {
        match self {
            Motion::Pull => -1.0,
            Motion::Release => 1.0,
        }
    }

    /// The name files and the command line use: `pull` or `release`.
    pub fn name(self) -> &'static str {
        match self {
            Motion::Pull => "pull",
            Motion::Release => "release",
        }
    }

    /// The names [`Motion::from_name`] takes, with what each means: every front end (the
    /// command line, experiment files, Python) says this when a name is none of them.
    pub const CHOICES: &'static str =
        "`pull` (the actuator pulls the tendon in: a loading step) or `release` (it lets it out: an unloading step)";

    /// The motion called `name` (`pull` or `release`, as [`Motion::name`] gives them), None
    /// for any other name; the front ends trim blanks around the name first.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "pull" => Some(Motion::Pull),
            "release" => Some(Motion::Release),
            _ => None,
        }
    }
}

/// Coulomb friction between a tendon and its channels, in full slip (the capstan law along
/// the tendon, docs/friction.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Friction {
    /// Friction coefficient mu_i (dimensionless, >= 0); 0 is the frictionless tendon.
    pub coefficient: f64,
    /// The motion being modelled; default [`Motion::Pull`].
    pub motion: Motion,
}

impl Friction {
    /// Friction `coefficient` mu while the actuator pulls the tendon in.
    pub fn pull(coefficient: f64) -> Self {
        Friction {
            coefficient,
            motion: Motion::Pull,
        }
    }
}

/// One tendon, modelled as a Cosserat string (section 3 of the paper), driven by its
/// tension or by the pull-in of its actuator ([`Actuation`]), frictionless unless it has a
/// [`Friction`].
#[derive(Clone, Debug)]
pub struct Tendon {
    /// Path in the cross-section along s.
    pub routing: Routing,
    /// How it is driven: a tension or a pull-in.
    pub actuation: Actuation,
    /// Arc length l_i where it is attached to the backbone (m), in (0, L]; `None` means
    /// the tip.
    pub termination: Option<f64>,
    /// Axial stiffness E_t A_t of the tendon (N); `None` (the default): inextensible.
    pub stiffness: Option<f64>,
    /// Length of tendon between the base, where it enters the backbone, and the actuator
    /// (m, >= 0): it stretches with the rest of an elastic tendon. Default 0.
    pub free_length: f64,
    /// Friction in its channels; `None` (the default) or a coefficient of 0: frictionless.
    pub friction: Option<Friction>,
}

impl Tendon {
    /// A tendon along `routing` at `tension` (N), ending at the tip.
    pub fn new(routing: Routing, tension: f64) -> Self {
        Tendon {
            routing,
            actuation: Actuation::Tension(tension),
            termination: None,
            stiffness: None,
            free_length: 0.0,
            friction: None,
        }
    }

    /// A displacement-controlled tendon along `routing` whose actuator pulls it in by
    /// `displacement` q (m), ending at the tip; its starting tension is estimated.
    pub fn pulled(routing: Routing, displacement: f64) -> Self {
        Tendon {
            actuation: Actuation::PullIn {
                displacement,
                start: None,
            },
            ..Tendon::new(routing, 0.0)
        }
    }

    /// The tension (N) the model loads the rod with: the input of a tension-controlled
    /// tendon; for a displacement-controlled one the tension Newton starts from (0 when the
    /// solver is to estimate it).
    pub fn tension(&self) -> f64 {
        match self.actuation {
            Actuation::Tension(tension) => tension,
            Actuation::PullIn { start, .. } => start.unwrap_or(0.0),
        }
    }

    /// The actuator pull-in q (m) of a displacement-controlled tendon; `None` for a
    /// tension-controlled one.
    pub fn displacement(&self) -> Option<f64> {
        match self.actuation {
            Actuation::Tension(_) => None,
            Actuation::PullIn { displacement, .. } => Some(displacement),
        }
    }

    /// Makes the tendon tension-controlled at `tension` (N).
    pub fn set_tension(&mut self, tension: f64) {
        self.actuation = Actuation::Tension(tension);
    }

    /// Makes the tendon displacement-controlled with pull-in `displacement` (m), its
    /// starting tension estimated by the solver.
    pub fn set_displacement(&mut self, displacement: f64) {
        self.actuation = Actuation::PullIn {
            displacement,
            start: None,
        };
    }

    /// Sets the tension the model uses without changing how the tendon is driven: the input
    /// of a tension-controlled tendon, the starting tension of a displacement-controlled one
    /// (a solver's current iterate).
    pub(crate) fn hold_tension(&mut self, tension: f64) {
        match &mut self.actuation {
            Actuation::Tension(t) => *t = tension,
            Actuation::PullIn { start, .. } => *start = Some(tension),
        }
    }

    /// The same tendon ending at arc length `s` (m).
    pub fn ending_at(mut self, s: f64) -> Self {
        self.termination = Some(s);
        self
    }

    /// The same tendon, elastic with axial stiffness E_t A_t = `stiffness` (N) and
    /// `free_length` (m) between the base and the actuator.
    pub fn elastic(mut self, stiffness: f64, free_length: f64) -> Self {
        self.stiffness = Some(stiffness);
        self.free_length = free_length;
        self
    }

    /// The signed turns this tendon's path makes about the backbone from the base to its
    /// end, on a rod of `length` L (m) ([`Routing::turns_between`]): a helical routing of
    /// `turns` per rod length ending at l makes `turns * l / L`; 0 for a straight routing;
    /// a custom one its winding angle over 2 pi. A helix of one turn per rod length ending
    /// at L/2 makes 0.5 turns.
    pub fn turns(&self, length: f64) -> f64 {
        self.routing.turns_between(0.0, self.end(length), length)
    }

    /// The same tendon with `friction` in its channels.
    pub fn with_friction(mut self, friction: Friction) -> Self {
        self.friction = Some(friction);
        self
    }

    /// The friction of this tendon when it has any: `Some` only for a coefficient > 0, so
    /// that a coefficient of 0 is the frictionless tendon, solved exactly as without one.
    pub fn active_friction(&self) -> Option<Friction> {
        self.friction.filter(|f| f.coefficient > 0.0)
    }

    /// Termination arc length on a rod of `length` L (m).
    pub fn end(&self, length: f64) -> f64 {
        self.termination.unwrap_or(length)
    }

    /// The tendon's compliance to tension in its pull-in (m/N): its unstretched length
    /// L0 = `reference_length` + free length over E_t A_t, 0 when inextensible. A tendon
    /// taut at tension tau stretches by tau L0 / (E_t A_t) (docs/actuation.md).
    pub fn compliance(&self, reference_length: f64) -> f64 {
        self.stiffness
            .map_or(0.0, |k| (reference_length + self.free_length) / k)
    }
}
