//! Robots changed as a calibration changes them: tendon offsets scaled, and the whole robot
//! described in a turned world frame.
#![allow(non_snake_case)]

use crate::model::loads::{Field, PointLoad};
use crate::model::robot::Robot;
use crate::model::routing::{Routing, RoutingPoint};
use nalgebra::Matrix3;
use std::sync::Arc;

/// `routing` with its offset r(s) (and so r', r'') multiplied by `factor`.
pub fn scaled_routing(routing: &Routing, factor: f64) -> Routing {
    match routing {
        Routing::Straight { x, y } => Routing::straight(factor * x, factor * y),
        Routing::Helical { radius, turns, phase } => Routing::helical(factor * radius, *turns, *phase),
        Routing::Custom(f) => {
            let f = Arc::clone(f);
            Routing::custom(move |s, length| {
                let p = f(s, length);
                RoutingPoint {
                    r: p.r * factor,
                    r_s: p.r_s * factor,
                    r_ss: p.r_ss * factor,
                }
            })
        }
    }
}

/// The same robot described in a world frame turned by `rotation` (new world coordinates =
/// `rotation` times old): base pose, distributed loads, tip and point wrenches are rotated;
/// the body-frame data (rod, routings) are unchanged, and so is the shape relative to the base.
pub fn rotate_world(robot: &Robot, rotation: &Matrix3<f64>) -> Robot {
    let T = *rotation;
    let mut out = robot.clone();
    out.base_position = T * robot.base_position;
    out.base_rotation = T * robot.base_rotation;
    let turn = |field: &Field| match field {
        Field::Constant(v) => Field::Constant(T * v),
        Field::Varying(f) => {
            let f = Arc::clone(f);
            Field::Varying(Arc::new(move |s| T * f(s)))
        }
    };
    out.loads.distributed_force = turn(&robot.loads.distributed_force);
    out.loads.distributed_moment = turn(&robot.loads.distributed_moment);
    out.loads.tip_force = T * robot.loads.tip_force;
    out.loads.tip_moment = T * robot.loads.tip_moment;
    out.loads.point = robot
        .loads
        .point
        .iter()
        .map(|p| PointLoad {
            s: p.s,
            force: T * p.force,
            moment: T * p.moment,
        })
        .collect();
    out
}
