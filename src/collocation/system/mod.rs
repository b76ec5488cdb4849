//! Assembly of the collocation system: residual vector and sparse Jacobian.
//!
//! The layout of unknowns and rows, and the block pattern this fills, are in
//! [`super::unknowns`].
//!
//! The pattern is built once per mesh; each Newton
//! iteration refills the values in the same order. The Jacobian is exact: interval blocks by
//! the chain rule of [`residual::interval_jacobian`], the base and tip blocks in closed form
//! ([`end_rows`]), the jump blocks by num-dual dual numbers run through the same generic
//! residual code.

mod ahead;
mod columns;
mod friction6;
mod inputs;
mod jump;
mod lanes;
mod quarters;

use super::end_rows;
use super::friction::{self, Profile};
use super::residual::{self, Block, Delta, IntervalFactors, IntervalSites};
use super::stage;
use super::unknowns::{self, BASE_COLUMNS, BASE_ROWS, NODE, link_row, tip_row};
use crate::error::Result;
use crate::mesh::Mesh;
use crate::model::equations::{Model, Site};
use crate::model::linearize;
use crate::solution::State;
pub(crate) use columns::TensionSink;
use nalgebra::Vector6;

/// The parameters whose exact residual columns [`System::parameter_columns`] gives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Columns {
    /// Every tendon's tension (N), in the robot's order.
    Tensions,
    /// The six diagonal stiffnesses of a uniform section: kse = (GA, GA, EA) (N), then
    /// kbt = (EIxx, EIyy, GJ) (N m^2).
    Stiffness,
}

/// The collocation system on one mesh at one load factor.
pub struct System<'a> {
    /// The model (robot and its inputs: tensions, factors, a traced parameter). The sites
    /// depend on its external loads, not on its tensions, which a solver may change in place
    /// ([`Model::tensions`]) between evaluations.
    pub model: Model<'a>,
    /// The mesh.
    pub mesh: Mesh,
    /// Sites of each link: `Some` for intervals, `None` for jumps.
    interval_sites: Vec<Option<IntervalSites>>,
    /// Site at each node.
    node_sites: Vec<Site>,
    /// Evaluations of eq. 13 in one residual or Jacobian pass.
    rate_evaluations: usize,
    /// The tension profile of the tendons with friction (docs/friction.md), whose intervals
    /// are then collocated with it; `None` without friction.
    pub(crate) friction: Option<Profile<'a>>,
    /// What the buffers' sites were computed from, for [`System::into_parts`].
    inputs: inputs::SiteInputs,
    /// The order-6 estimate's quarter sites on these sites, once it asked for them.
    quarters: quarters::Quarters,
}

/// The buffers a [`System`] fills for its mesh (the sites) and its model's tensions, which
/// a workspace keeps between the systems of the solves on its mesh
/// ([`System::with_buffers`], [`System::into_parts`]).
#[derive(Default)]
pub(crate) struct SystemBuffers {
    tensions: Vec<f64>,
    interval_sites: Vec<Option<IntervalSites>>,
    node_sites: Vec<Site>,
    /// The load factor and traced parameter of the model whose sites the buffers hold
    /// (the system that gave them back), None before any: what
    /// [`SystemBuffers::has_sites_of`] checks.
    sites_of: Option<(f64, Option<(crate::model::parameter::Parameter, f64)>)>,
    /// What the sites were computed from ([`System::with_buffers`] keeps them when the same).
    inputs: inputs::SiteInputs,
    /// The quarter sites on these sites, if computed (kept with them).
    quarters: quarters::Quarters,
}

impl SystemBuffers {
    /// Whether the sites held can be those of `model` on `mesh` (the robot aside, which the
    /// caller vouches for): a system with its load factor and traced parameter left them,
    /// one per node and link of `mesh` (the only inputs besides the robot and the mesh that
    /// the sites depend on).
    pub(crate) fn has_sites_of(&self, model: &Model, mesh: &Mesh) -> bool {
        self.sites_of == Some((model.load_factor, model.parameter))
            && self.node_sites.len() == mesh.nodes.len()
            && self.interval_sites.len() + 1 == mesh.nodes.len()
    }
}

impl<'a> System<'a> {
    /// The system of `model` on `mesh`.
    pub fn new(model: Model<'a>, mesh: Mesh) -> Self {
        Self::assembled(model, mesh, SystemBuffers::default())
    }

    /// The system of `model` on `mesh`, its sites computed into `buffers`.
    fn assembled(model: Model<'a>, mesh: Mesh, buffers: SystemBuffers) -> Self {
        let mut sys = System {
            model,
            mesh,
            interval_sites: buffers.interval_sites,
            node_sites: buffers.node_sites,
            rate_evaluations: 0,
            friction: None,
            inputs: buffers.inputs,
            quarters: buffers.quarters,
        };
        sys.set_factors(sys.model.tension_factor, sys.model.load_factor);
        sys
    }

    /// The system of `model` on `mesh` with the sites `buffers` hold, without computing
    /// them again: `buffers` must hold those of a system of the same robot on this mesh
    /// with `model`'s load factor and traced parameter ([`SystemBuffers::has_sites_of`]; the
    /// caller vouches for the robot: the sensitivities of a [`crate::Solver`]'s last answer,
    /// whose Jacobian that system's verdict evaluated).
    pub(crate) fn with_kept_sites(model: Model<'a>, mesh: Mesh, buffers: SystemBuffers) -> Self {
        debug_assert!(buffers.has_sites_of(&model, &mesh));
        let mut sys = System {
            model,
            mesh,
            interval_sites: buffers.interval_sites,
            node_sites: buffers.node_sites,
            rate_evaluations: 0,
            friction: None,
            inputs: buffers.inputs,
            quarters: buffers.quarters,
        };
        sys.count_rate_evaluations();
        sys
    }

    /// The mesh, and the buffers of the sites and the model's tensions for a later
    /// [`System::with_buffers`].
    pub(crate) fn into_parts(mut self) -> (Mesh, SystemBuffers) {
        self.inputs.record(&self.model, &self.mesh);
        let buffers = SystemBuffers {
            tensions: self.model.tensions,
            interval_sites: self.interval_sites,
            node_sites: self.node_sites,
            sites_of: Some((self.model.load_factor, self.model.parameter)),
            inputs: self.inputs,
            quarters: self.quarters,
        };
        (self.mesh, buffers)
    }

    /// Changes the tension and external-load factors of the model (recomputes the sites,
    /// whose external loads the latter scales).
    pub fn set_factors(&mut self, tension_factor: f64, load_factor: f64) {
        self.model.tension_factor = tension_factor;
        self.model.load_factor = load_factor;
        self.refresh();
    }

    /// Sets one input of the model to `value` ([`Model::set`]) and recomputes the sites
    /// when the external loads changed.
    pub fn set_parameter(&mut self, parameter: crate::model::parameter::Parameter, value: f64) {
        if self.model.set(parameter, value) {
            self.refresh();
        }
    }

    /// Recomputes the sites from the model (and forgets the quarter sites on the old ones).
    fn refresh(&mut self) {
        self.quarters.forget();
        let model = &self.model;
        self.node_sites.clear();
        self.node_sites
            .extend(self.mesh.nodes.iter().map(|n| model.site_on(n.s, n.segment_end)));
        self.interval_sites.clear();
        let node_sites = &self.node_sites;
        self.interval_sites.extend((0..self.mesh.nodes.len() - 1).map(|k| {
            (!self.mesh.is_jump(k)).then(|| IntervalSites {
                start: node_sites[k],
                mid: model.site(0.5 * (self.mesh.nodes[k].s + self.mesh.nodes[k + 1].s)),
                end: node_sites[k + 1],
            })
        }));
        self.count_rate_evaluations();
    }

    /// Counts the evaluations of eq. 13 in one pass over the sites.
    fn count_rate_evaluations(&mut self) {
        // Each interval evaluates eq. 13 at its midpoint and end, and at its start unless
        // the interval before it already did (the shared node is evaluated once).
        let mut shared = false;
        self.rate_evaluations = self
            .interval_sites
            .iter()
            .map(|sites| {
                let count = match sites {
                    Some(_) if shared => 2,
                    Some(_) => 3,
                    None => 0,
                };
                shared = sites.is_some();
                count
            })
            .sum();
    }

    /// Evaluations of eq. 13 in one [`System::residual`] or [`System::jacobian`] pass.
    pub fn rate_evaluations(&self) -> usize {
        self.rate_evaluations
    }

    /// Number of unknowns (= rows).
    pub fn unknowns(&self) -> usize {
        unknowns::unknowns(self.mesh.nodes.len())
    }

    /// Arc length a residual row belongs to.
    pub fn row_position(&self, row: usize) -> f64 {
        unknowns::row_position(&self.mesh, self.model.robot.length(), row)
    }

    /// The residual at the states `x` (one per mesh node), written into `out`.
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    pub fn residual(&self, x: &[State], out: &mut [f64]) -> Result<()> {
        if let Some(profile) = &self.friction {
            return self.friction_residual(profile, x, out);
        }
        // Runs of four intervals of one segment go to the lanes (`residual_group`).
        let mut group = None;
        self.rows(x, out, |k, sites, seg, a, b, start| {
            if let Some((r, _, end)) = self.residual_group(k, x, start, &mut group)? {
                return Ok((r, end));
            }
            residual::interval(&self.model, sites, seg, a, b, start).map(|(r, _, end)| (r, end))
        })
    }

    /// [`System::residual`] with every midpoint's strain kept below its last place
    /// ([`stage::interval_split`]): the order-4 rows of the order-6 answer's correction.
    /// Not for friction (whose order-6 answer is not built).
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    pub(crate) fn residual_split(&self, x: &[State], out: &mut [f64]) -> Result<()> {
        self.rows(x, out, |_, sites, seg, a, b, start| {
            stage::interval_split(&self.model, sites, seg, a, b, start)
        })
    }

    /// [`System::order6_residual`] with every stage's strain kept below its last place
    /// ([`stage::interval_order6_split`]), given the node rates at `x` (`rates`, one per
    /// node, as [`System::residual_rates`] gives them): the order-6 rows of the order-6
    /// answer's defect. Not for friction.
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    pub(crate) fn order6_residual_split(&self, x: &[State], out: &mut [f64], rates: &[Vector6<f64>]) -> Result<()> {
        self.rows(x, out, |k, sites, seg, a, b, _| {
            let quarters = self.quarters(k);
            let r = stage::interval_order6_split(&self.model, sites, quarters, seg, a, b, &rates[k], &rates[k + 1])?;
            Ok((r, rates[k + 1]))
        })
    }

    /// [`System::residual`], and the rates (v', u') of eq. 13 its intervals evaluated at
    /// their nodes into `rates` (one per node; a node between two jumps is left as it was):
    /// the values [`System::order6_residual_with`] evaluates at the same states, kept so that
    /// the error estimate at a converged state need not evaluate them again. Returns whether
    /// `rates` were written: not for tendons with friction, whose intervals do not give them.
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    pub(crate) fn residual_rates(&self, x: &[State], out: &mut [f64], rates: &mut [Vector6<f64>]) -> Result<bool> {
        if self.friction.is_some() {
            return self.residual(x, out).map(|()| false);
        }
        let mut group = None;
        self.rows(x, out, |k, sites, seg, a, b, start| {
            let (r, start, end) = match self.residual_group(k, x, start, &mut group)? {
                Some(grouped) => grouped,
                None => residual::interval(&self.model, sites, seg, a, b, start)?,
            };
            (rates[k], rates[k + 1]) = (start, end);
            Ok((r, end))
        })?;
        Ok(true)
    }

    /// The residual of the order-6 scheme at the states `x` (converged for the order-4
    /// scheme) into `out`: base, jump and tip rows as in [`System::residual`], interval rows
    /// by [`residual::interval_order6`]. `local[k]` gets link k's local error, the max-norm
    /// of its order-6 rows (0 for jumps), and `rates[k]` the rates (v', u') at node k. The
    /// right-hand side of the deferred correction.
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    pub fn order6_residual(
        &self,
        x: &[State],
        out: &mut [f64],
        local: &mut [f64],
        rates: &mut [Vector6<f64>],
    ) -> Result<()> {
        self.order6_residual_with(x, out, local, rates, false)
    }

    /// [`System::order6_residual`]; when `known`, `rates` already hold the node rates at `x`
    /// ([`System::residual_rates`] at the same states and inputs, bit for bit the values this
    /// would evaluate) and intervals read them instead of evaluating eq. 13 at their nodes.
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    pub(crate) fn order6_residual_with(
        &self,
        x: &[State],
        out: &mut [f64],
        local: &mut [f64],
        rates: &mut [Vector6<f64>],
        known: bool,
    ) -> Result<()> {
        local.fill(0.0);
        if let Some(profile) = &self.friction {
            return self.friction_order6(profile, x, out, local, rates);
        }
        // With the node rates known the intervals are independent: runs of four go to the
        // lanes (`order6_group`).
        let mut group = None;
        self.rows(x, out, |k, sites, seg, a, b, start| {
            let (start, end) = if known {
                (rates[k], rates[k + 1])
            } else {
                self.end_rates(sites, seg, a, b, start)?
            };
            (rates[k], rates[k + 1]) = (start, end);
            let grouped = known.then(|| self.order6_group(k, x, rates, &mut group)).flatten();
            let r = match grouped {
                Some(r) => r,
                None => {
                    let quarters = self.quarters(k);
                    residual::interval_order6(&self.model, sites, quarters, seg, a, b, &start, &end)?
                }
            };
            local[k] = r.amax();
            Ok((r, end))
        })
    }

    /// The rates (v', u') of eq. 13 at an interval's two nodes `a` and `b` (segment end
    /// `seg`): the start's given by the link before (`start`) or evaluated here.
    ///
    /// # Errors
    /// A model breakdown at either node.
    pub(super) fn end_rates(
        &self,
        sites: &IntervalSites,
        seg: f64,
        a: &State,
        b: &State,
        start: Option<Vector6<f64>>,
    ) -> Result<(Vector6<f64>, Vector6<f64>)> {
        let start = match start {
            Some(r) => r,
            None => linearize::rates(&self.model, &sites.start, seg, &a.R, &a.v, &a.u)?,
        };
        Ok((start, linearize::rates(&self.model, &sites.end, seg, &b.R, &b.v, &b.u)?))
    }

    /// Writes the base, link and tip rows at `x` into `out`, interval k's rows by `interval(k,
    /// sites, segment end, node k, node k + 1, rates at node k)`, which returns them with the
    /// rates at node k + 1 (shared with the next interval, so each node's rates are evaluated
    /// once).
    pub(super) fn rows<F>(&self, x: &[State], out: &mut [f64], mut interval: F) -> Result<()>
    where
        F: FnMut(
            usize,
            &IntervalSites,
            f64,
            &State,
            &State,
            Option<Vector6<f64>>,
        ) -> Result<(Block<f64>, Vector6<f64>)>,
    {
        let z = Delta::<f64>::zeros();
        let base = residual::base(&self.model, &x[0], &z);
        out[..BASE_ROWS].copy_from_slice(base.as_slice());
        let links = x.len() - 1;
        let mut node_rates = None;
        for k in 0..links {
            let r = match &self.interval_sites[k] {
                Some(sites) => {
                    let seg = self.mesh.nodes[k].segment_end;
                    let (r, end) = interval(k, sites, seg, &x[k], &x[k + 1], node_rates)?;
                    node_rates = Some(end);
                    r
                }
                None => {
                    node_rates = None;
                    residual::jump(
                        &self.model,
                        (&self.node_sites[k], &self.node_sites[k + 1]),
                        &x[k],
                        &x[k + 1],
                        &z,
                        &z,
                    )?
                }
            };
            out[link_row(k)..link_row(k + 1)].copy_from_slice(r.as_slice());
        }
        let tip = residual::tip(&self.model, &self.node_sites[links], &x[links], &z)?;
        out[tip_row(x.len())..].copy_from_slice(tip.as_slice());
        Ok(())
    }

    /// The residual into `out` and the Jacobian values, in [`pattern`](super::unknowns::pattern) order, into `values`.
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    pub fn jacobian(&self, x: &[State], out: &mut [f64], values: &mut [f64]) -> Result<()> {
        self.jacobian_with(x, out, values, None, None, None)
    }

    /// [`System::jacobian`] that keeps, when given `kept` (one per link, friction aside),
    /// eq. 13's factored matrix at each interval's points ([`residual::interval_jacobian_keeping`];
    /// a start shared with the interval before copied from its end) for the mass.
    ///
    /// # Errors
    /// As [`System::jacobian`].
    pub(crate) fn jacobian_keeping(
        &self,
        x: &[State],
        out: &mut [f64],
        values: &mut [f64],
        kept: Option<&mut [IntervalFactors]>,
    ) -> Result<()> {
        self.jacobian_with(x, out, values, kept, None, None)
    }

    /// [`System::jacobian`], keeping each interval's factors in `kept` as
    /// [`System::jacobian_keeping`] does, or writing each interval's tension rows into the
    /// columns `tensions` gives, with its buffers ([`System::jacobian_and_tensions`]); not
    /// both (a point keeps its factors or forms its tension rows); `rates` (as
    /// [`System::jacobian_rates`]) with either or alone.
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    fn jacobian_with(
        &self,
        x: &[State],
        out: &mut [f64],
        values: &mut [f64],
        mut kept: Option<&mut [IntervalFactors]>,
        mut tensions: Option<(&mut TensionSink, &mut [f64])>,
        mut rates: Option<&mut [Vector6<f64>]>,
    ) -> Result<()> {
        debug_assert!(
            !(kept.is_some() && tensions.is_some()),
            "kept factors exclude tension rows"
        );
        let n = self.unknowns();
        end_rows::base_rows(&self.model, &x[0], out, values);
        let mut at = BASE_ROWS * BASE_COLUMNS;
        let (links, width) = (x.len() - 1, 2 * NODE);
        // Linearization at the shared node of consecutive intervals, evaluated once: interval
        // k writes its end node's into `lins[(k + 1) % 2]`, where interval k + 1 reads it
        // (`shared`: the link before was an interval). Runs of four intervals of one segment
        // go to the lane kernel (`interval_group`) unless eq. 13's factors are kept.
        let (mut lins, mut shared, mut k) = ([linearize::Linearization::zeros(); 2], false, 0);
        while k < links {
            let rows = link_row(k)..link_row(k + 1);
            if let Some(sites) = &self.interval_sites[k] {
                let seg = self.mesh.nodes[k].segment_end;
                if let Some(profile) = &self.friction {
                    if let Some(lins) = self.friction_group(profile, k, x, Some(&mut values[at..]))? {
                        for (j, lin) in lins.into_iter().enumerate() {
                            out[link_row(k + j)..link_row(k + j + 1)].copy_from_slice(lin.residual.as_slice());
                            profile.keep(k + j, lin);
                        }
                        (shared, k, at) = (true, k + 4, at + 4 * NODE * width);
                        continue;
                    }
                    let (length, block) = (self.model.robot.length(), &mut values[at..at + NODE * width]);
                    let lin = friction::interval(profile, length, k, sites, seg, &x[k], &x[k + 1], Some(block))?;
                    out[rows].copy_from_slice(lin.residual.as_slice());
                    profile.keep(k, lin);
                } else if kept.is_none()
                    && self.interval_group(
                        k,
                        x,
                        out,
                        &mut values[at..],
                        &mut lins,
                        shared,
                        rates.as_deref_mut(),
                        &mut tensions,
                    )?
                {
                    (shared, k, at) = (true, k + 4, at + 4 * NODE * width);
                    continue;
                } else {
                    let block = &mut values[at..at + NODE * width];
                    let [even, odd] = &mut lins;
                    let (start, end) = if k % 2 == 0 { (&*even, odd) } else { (&*odd, even) };
                    let start = shared.then_some(start);
                    let ends = (&x[k], &x[k + 1]);
                    let sink = tensions
                        .as_mut()
                        .map(|(sink, columns)| sink.interval(shared, k, columns, n));
                    let r = match (kept.as_deref_mut(), rates.as_deref_mut()) {
                        (None, Some(rates)) => {
                            let (r, at_start) = residual::interval_jacobian_as_residual(
                                &self.model,
                                sites,
                                seg,
                                ends,
                                start,
                                block,
                                sink,
                                end,
                            )?;
                            (rates[k], rates[k + 1]) = (at_start, end.rates);
                            r
                        }
                        (None, None) => {
                            residual::interval_jacobian_into(&self.model, sites, seg, ends, start, block, sink, end)?
                        }
                        (Some(kept), rates) => {
                            if start.is_some() {
                                kept[k].start = kept[k - 1].end.clone();
                            }
                            let (r, at_start) = residual::interval_jacobian_keeping(
                                &self.model,
                                sites,
                                seg,
                                ends,
                                start,
                                block,
                                &mut kept[k],
                                rates.is_some(),
                                end,
                            )?;
                            if let Some(rates) = rates {
                                (rates[k], rates[k + 1]) = (at_start, end.rates);
                            }
                            r
                        }
                    };
                    shared = true;
                    out[rows].copy_from_slice(r.as_slice());
                }
            } else {
                shared = false;
                self.jump_rows(k, x, out, &mut values[at..at + NODE * width])?;
            }
            at += NODE * width;
            k += 1;
        }
        end_rows::tip_rows(
            &self.model,
            &self.node_sites[links],
            &x[links],
            &mut out[tip_row(x.len())..],
            &mut values[at..],
        )
    }

    /// The states `x` moved by `alpha` times the scaled Newton step `step`
    /// ([`unknowns::retract`]), written into `out`.
    pub fn retract(&self, x: &[State], step: &[f64], alpha: f64, out: &mut Vec<State>) {
        unknowns::retract(x, step, alpha, self.model.robot.length(), out);
    }

    /// Sites of link k when it is an interval.
    pub fn interval_sites(&self, k: usize) -> Option<&IntervalSites> {
        self.interval_sites[k].as_ref()
    }
}
