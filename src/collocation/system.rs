//! Assembly of the collocation system: residual vector and sparse Jacobian.
//!
//! Unknowns are ordered node by node, 12 per node (dp/L, dtheta, dv, du L). Rows are the 6
//! base conditions, then 12 per link (an interval's collocation equations or a breakpoint's
//! jump conditions), then the 6 tip conditions, so the Jacobian is almost block diagonal:
//!
//! ```text
//!            node 0      node 1      node 2            node N
//!          [p R v u ]  [p R v u ]  [p R v u ]        [p R v u ]
//! base   6 [ X X . . ]
//! link 0 12[ X X X X ]  [ X X X X ]
//! link 1 12             [ X X X X ]  [ X X X X ]
//!   ...                                     ...
//! link N-1                                       ... [ X X X X ]
//! tip    6                                           [ . X X X ]
//! ```
//!
//! The base rows depend only on p and R of node 0, the tip rows on R, v, u of node N; each
//! link block is a dense 12 x 24. The pattern is built once per mesh; each Newton
//! iteration refills the values in the same order. The Jacobian is exact: interval blocks by
//! the chain rule of [`residual::interval_jacobian`], the base, jump and tip blocks by
//! num-dual dual numbers run through the same generic residual code.

use super::residual::{self, Delta, IntervalSites};
use crate::error::Result;
use crate::mesh::Mesh;
use crate::model::equations::{Model, Site};
use crate::so3;
use crate::solution::State;
use nalgebra::{SVector, Vector3};
use num_dual::{Dual64, DualSVec64};

/// Unknowns per node.
pub const NODE: usize = 12;

type D12 = DualSVec64<12>;

/// The collocation system on one mesh at one load factor.
pub struct System<'a> {
    /// The model (robot and load factor).
    pub model: Model<'a>,
    /// The mesh.
    pub mesh: Mesh,
    /// Sites of each link: `Some` for intervals, `None` for jumps.
    interval_sites: Vec<Option<IntervalSites>>,
    /// Site at each node.
    node_sites: Vec<Site>,
}

/// Stored non-zeros of the Jacobian on `mesh`: the base block (6 x 6), one 12 x 24 block per
/// link and the tip block (6 x 9); the length of [`pattern`].
pub fn nonzeros(mesh: &Mesh) -> usize {
    36 + (mesh.nodes.len() - 1) * NODE * 2 * NODE + 54
}

/// The (row, column) pattern of the Jacobian in assembly order.
pub fn pattern(mesh: &Mesh) -> Vec<(usize, usize)> {
    let nodes = mesh.nodes.len();
    let links = nodes - 1;
    let mut out = Vec::with_capacity(nonzeros(mesh));
    for r in 0..6 {
        for c in 0..6 {
            out.push((r, c));
        }
    }
    for k in 0..links {
        for r in 0..NODE {
            for c in 0..2 * NODE {
                out.push((6 + k * NODE + r, k * NODE + c));
            }
        }
    }
    let (row0, col0) = (6 + links * NODE, (nodes - 1) * NODE);
    for r in 0..6 {
        for c in 3..NODE {
            out.push((row0 + r, col0 + c));
        }
    }
    out
}

impl<'a> System<'a> {
    /// The system of `model` on `mesh`.
    pub fn new(model: Model<'a>, mesh: Mesh) -> Self {
        let mut sys = System {
            model,
            mesh,
            interval_sites: Vec::new(),
            node_sites: Vec::new(),
        };
        sys.set_factors(model.tension_factor, model.load_factor);
        sys
    }

    /// Changes the tension and external-load factors of the model (recomputes the sites,
    /// whose external loads the latter scales).
    pub fn set_factors(&mut self, tension_factor: f64, load_factor: f64) {
        self.model.tension_factor = tension_factor;
        self.model.load_factor = load_factor;
        let model = self.model;
        self.node_sites = self.mesh.nodes.iter().map(|n| model.site(n.s)).collect();
        self.interval_sites = (0..self.mesh.nodes.len() - 1)
            .map(|k| {
                (!self.mesh.is_jump(k)).then(|| IntervalSites {
                    start: self.node_sites[k],
                    mid: model.site(0.5 * (self.mesh.nodes[k].s + self.mesh.nodes[k + 1].s)),
                    end: self.node_sites[k + 1],
                })
            })
            .collect();
    }

    /// Number of unknowns (= rows).
    pub fn unknowns(&self) -> usize {
        self.mesh.nodes.len() * NODE
    }

    /// Arc length a residual row belongs to.
    pub fn row_position(&self, row: usize) -> f64 {
        let links = self.mesh.nodes.len() - 1;
        if row < 6 {
            0.0
        } else if row >= 6 + links * NODE {
            self.model.robot.length()
        } else {
            let k = (row - 6) / NODE;
            0.5 * (self.mesh.nodes[k].s + self.mesh.nodes[k + 1].s)
        }
    }

    /// The residual at the states `x` (one per mesh node), written into `out`.
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    pub fn residual(&self, x: &[State], out: &mut [f64]) -> Result<()> {
        let z = Delta::<f64>::zeros();
        let base = residual::base(&self.model, &x[0], &z);
        out[..6].copy_from_slice(base.as_slice());
        let links = x.len() - 1;
        // Rates at the shared node of consecutive intervals, evaluated once.
        let mut node_rates = None;
        for k in 0..links {
            let r = match &self.interval_sites[k] {
                Some(sites) => {
                    let seg = self.mesh.nodes[k].segment_end;
                    let (r, end) = residual::interval(&self.model, sites, seg, &x[k], &x[k + 1], node_rates)?;
                    node_rates = Some(end);
                    r
                }
                None => {
                    node_rates = None;
                    residual::jump(&self.model, &self.node_sites[k], &x[k], &x[k + 1], &z, &z)?
                }
            };
            out[6 + k * NODE..6 + (k + 1) * NODE].copy_from_slice(r.as_slice());
        }
        let tip = residual::tip(&self.model, &self.node_sites[links], &x[links], &z)?;
        out[6 + links * NODE..].copy_from_slice(tip.as_slice());
        Ok(())
    }

    /// The residual into `out` and the Jacobian values, in [`pattern`] order, into `values`.
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    pub fn jacobian(&self, x: &[State], out: &mut [f64], values: &mut [f64]) -> Result<()> {
        let seed12 = || Delta::<D12>::from_fn(|i, _| D12::from(0.0).derivative(i));
        let mut at = 0;
        let base = residual::base(&self.model, &x[0], &seed12());
        for (r, d) in base.iter().enumerate() {
            out[r] = d.re;
            let eps = derivative(&d.eps.0);
            values[at..at + 6].copy_from_slice(&eps.as_slice()[..6]);
            at += 6;
        }
        let links = x.len() - 1;
        let width = 2 * NODE;
        // Linearization at the shared node of consecutive intervals, evaluated once.
        let mut node_lin = None;
        for k in 0..links {
            let rows = 6 + k * NODE..6 + (k + 1) * NODE;
            if let Some(sites) = &self.interval_sites[k] {
                let seg = self.mesh.nodes[k].segment_end;
                let block = &mut values[at..at + NODE * width];
                let (r, end) = residual::interval_jacobian(&self.model, sites, seg, &x[k], &x[k + 1], node_lin, block)?;
                node_lin = Some(end);
                out[rows].copy_from_slice(r.as_slice());
            } else {
                node_lin = None;
                // Jumps: one dual pass per unknown (they are few).
                for j in 0..width {
                    let da = Delta::<Dual64>::from_fn(|i, _| {
                        if i == j {
                            Dual64::from(0.0).derivative()
                        } else {
                            Dual64::from(0.0)
                        }
                    });
                    let db = Delta::<Dual64>::from_fn(|i, _| {
                        if i + NODE == j {
                            Dual64::from(0.0).derivative()
                        } else {
                            Dual64::from(0.0)
                        }
                    });
                    let r = residual::jump(&self.model, &self.node_sites[k], &x[k], &x[k + 1], &da, &db)?;
                    for (i, d) in r.iter().enumerate() {
                        out[6 + k * NODE + i] = d.re;
                        values[at + i * width + j] = d.eps;
                    }
                }
            }
            at += NODE * width;
        }
        let tip = residual::tip(&self.model, &self.node_sites[links], &x[links], &seed12())?;
        for (r, d) in tip.iter().enumerate() {
            out[6 + links * NODE + r] = d.re;
            values[at..at + 9].copy_from_slice(&derivative(&d.eps.0).as_slice()[3..]);
            at += 9;
        }
        Ok(())
    }

    /// The states `x` moved by `alpha` times the scaled Newton step `step` (12 per node:
    /// p += L dp, R = R exp(dtheta), v += dv, u += du / L), written into `out`.
    pub fn retract(&self, x: &[State], step: &[f64], alpha: f64, out: &mut Vec<State>) {
        let length = self.model.robot.length();
        out.clear();
        for (k, s) in x.iter().enumerate() {
            let d = |i: usize| Vector3::new(step[k * NODE + i], step[k * NODE + i + 1], step[k * NODE + i + 2]) * alpha;
            out.push(State {
                s: s.s,
                p: s.p + d(0) * length,
                R: s.R * so3::exp(&d(3)),
                v: s.v + d(6),
                u: s.u + d(9) / length,
            });
        }
    }

    /// Sites of link k when it is an interval.
    pub fn interval_sites(&self, k: usize) -> Option<&IntervalSites> {
        self.interval_sites[k].as_ref()
    }
}

/// The derivative part of a dual number (zero when it carries none).
fn derivative<const N: usize>(eps: &Option<SVector<f64, N>>) -> SVector<f64, N> {
    eps.unwrap_or_else(SVector::zeros)
}
