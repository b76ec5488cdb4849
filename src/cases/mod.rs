//! Known-answer cases shared by tests, benches, examples and the CLI: the paper's prototype
//! (section 5, data in docs/reference.md) with the 32 experiments of Table 2, its reference
//! tips, the closed-form answers of [`analytic`], the prototype in the paper's measurement
//! frame with the parameters the paper calibrated ([`prototype_in_paper_frame`],
//! [`table2_measurement`]), and seeded noise for synthetic measurements ([`GaussianNoise`]).

pub mod analytic;
mod noise;
mod paper_frame;

pub use noise::GaussianNoise;
pub use paper_frame::{
    PAPER_CALIBRATED_EULER_DEG, PAPER_CALIBRATED_YOUNGS_MODULUS, PAPER_NOMINAL_EULER_DEG, paper_frame_rotation,
    prototype_in_paper_frame, table2_measurement,
};

use crate::model::loads::Loads;
use crate::model::robot::Robot;
use crate::model::rod::Rod;
use crate::model::routing::Routing;
use crate::model::tendon::Tendon;
use nalgebra::{Matrix3, Vector3};

/// Prototype backbone length: 242 mm.
pub const LENGTH: f64 = 0.242;
/// Backbone radius: diameter 0.8 mm.
pub const RADIUS: f64 = 0.0004;
/// Nominal Young's modulus, 210 GPa (calibrated: 230 GPa).
pub const YOUNGS_MODULUS: f64 = 210e9;
/// Poisson's ratio, 0.3125.
pub const POISSON_RATIO: f64 = 0.3125;
/// Self weight of rod, disks and tendons, 0.47 N/m.
pub const WEIGHT_PER_LENGTH: f64 = 0.47;
/// Tendon offset from the backbone: 8 mm.
pub const TENDON_OFFSET: f64 = 0.008;
/// Tip loads of 10 g and 20 g masses (N).
pub const TIP_LOADS: [f64; 2] = [0.098, 0.196];

/// The prototype's base rotation: body z along world +x, body x along world -z
/// (rows `[[0,0,1],[0,1,0],[-1,0,0]]`).
pub fn prototype_base_rotation() -> Matrix3<f64> {
    Matrix3::new(0.0, 0.0, 1.0, 0.0, 1.0, 0.0, -1.0, 0.0, 0.0)
}

/// The five routings of Table 1: straight at (8, 0), (0, 8), (-8, 0), (0, -8) mm and a
/// helix of one full turn at 8 mm.
pub fn prototype_routings() -> [Routing; 5] {
    let r = TENDON_OFFSET;
    [
        Routing::straight(r, 0.0),
        Routing::straight(0.0, r),
        Routing::straight(-r, 0.0),
        Routing::straight(0.0, -r),
        Routing::helical(r, 1.0, 0.0),
    ]
}

/// The prototype with all five tendons slack, self weight along world -z, nominal E.
pub fn prototype() -> Robot {
    let mut robot = Robot::new(Rod::solid_circle(LENGTH, RADIUS, YOUNGS_MODULUS, POISSON_RATIO))
        .with_loads(Loads::self_weight(WEIGHT_PER_LENGTH, -Vector3::z()))
        .with_base(Vector3::zeros(), prototype_base_rotation());
    for routing in prototype_routings() {
        robot = robot.with_tendon(Tendon::new(routing, 0.0));
    }
    robot
}

/// One experiment of Table 2: which tendon is pulled, how hard, and the tip load.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Experiment {
    /// Tendon number as in the paper, 1..=5 (`None`: no tension).
    pub tendon: Option<usize>,
    /// Tension (N).
    pub tension: f64,
    /// Tip load magnitude (N), acting along world -z.
    pub tip_load: f64,
}

impl Experiment {
    /// The prototype loaded as in this experiment.
    pub fn robot(&self) -> Robot {
        let mut robot = prototype();
        if let Some(i) = self.tendon {
            robot.tendons[i - 1].set_tension(self.tension);
        }
        robot.loads.tip_force = Vector3::new(0.0, 0.0, -self.tip_load);
        robot
    }

    /// A short label, e.g. `T5 4.91 N + 0.196 N`.
    pub fn label(&self) -> String {
        match self.tendon {
            None => "no tension".into(),
            Some(i) if self.tip_load > 0.0 => format!("T{i} {:.2} N + {:.3} N tip", self.tension, self.tip_load),
            Some(i) => format!("T{i} {:.2} N", self.tension),
        }
    }
}

/// The 32 experiments of Table 2 ("all" means each of tendons 1-5 alone).
pub fn table2() -> Vec<Experiment> {
    let mut out = vec![Experiment {
        tendon: None,
        tension: 0.0,
        tip_load: 0.0,
    }];
    for tension in [0.98, 1.96, 2.94, 4.91] {
        for i in 1..=5 {
            out.push(Experiment {
                tendon: Some(i),
                tension,
                tip_load: 0.0,
            });
        }
    }
    for tip_load in TIP_LOADS {
        for i in 1..=4 {
            out.push(Experiment {
                tendon: Some(i),
                tension: 2.94,
                tip_load,
            });
        }
    }
    for tip_load in TIP_LOADS {
        out.push(Experiment {
            tendon: Some(5),
            tension: 4.91,
            tip_load,
        });
    }
    out.push(Experiment {
        tendon: Some(5),
        tension: 6.87,
        tip_load: 0.0,
    });
    out
}

/// Reference case S: tendon 1 at 2.94 N, no tip load.
pub fn case_s() -> Robot {
    Experiment {
        tendon: Some(1),
        tension: 2.94,
        tip_load: 0.0,
    }
    .robot()
}

/// Reference case H: helical tendon 5 at 4.91 N, tip force 0.196 N along -z.
pub fn case_h() -> Robot {
    Experiment {
        tendon: Some(5),
        tension: 4.91,
        tip_load: 0.196,
    }
    .robot()
}

/// Tip of case S (m), agreed by four independent solvers to about 2e-10 m (docs/reference.md).
pub const TIP_S: [f64; 3] = [0.151823122, 0.0, -0.159529649];
/// Tip of case H (m), same provenance.
pub const TIP_H: [f64; 3] = [0.155616146, 0.0596521926, -0.158035195];
