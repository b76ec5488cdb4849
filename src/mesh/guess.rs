//! Initial guesses: the rigid-equilibrium estimate, and a previous solution moved onto a
//! mesh ([`interpolate`]).
//!
//! The loads distal to each node are summed on the unloaded (reference) shape, giving an
//! estimate of the internal wrench there; the linear constitutive law turns it into strains,
//! and the poses are integrated from the base with those strains. For tendon-only loading
//! this is already the exact constant-curvature answer; for small external loads it is
//! linear beam theory; with no load it is the reference shape itself.
#![allow(non_snake_case)]

use crate::mesh::{Mesh, MeshNode, spare};
use crate::model::equations::{Model, Site, Which};
use crate::model::robot::RodModel;
use crate::model::routing::RoutingPoint;
use crate::simd::avx2_fma;
use crate::so3;
use crate::solution::{Node, Solution, State};
use nalgebra::{Matrix3, Vector3};

mod lanes;

/// The strain v at mesh node `node` whose translational coordinate is `v` (v* on a
/// Kirchhoff rod, [`crate::model::equations::Site::strain`]).
fn strain(model: &Model, node: &MeshNode, v: &Vector3<f64>) -> Vector3<f64> {
    match model.robot.rod_model {
        RodModel::Cosserat => *v,
        RodModel::Kirchhoff => model.robot.rod.reference_on(node.s, node.segment_end).v_star,
    }
}

/// Poses along the mesh integrated from the base with the node coordinates `v`, `u`
/// (midpoint rule on the Lie group); left and right limits at a breakpoint share a pose.
pub(crate) fn integrate_poses(
    model: &Model,
    nodes: &[MeshNode],
    strains: &[(Vector3<f64>, Vector3<f64>)],
) -> Vec<(Vector3<f64>, Matrix3<f64>)> {
    let mut out = Vec::with_capacity(nodes.len());
    integrate_poses_into(model, nodes, strains, &mut out);
    out
}

/// [`integrate_poses`] into `out` (cleared first), whose buffer a caller reuses. Inlined
/// into its callers (the capstan start compiles it for AVX2 and FMA with its passes).
#[inline(always)]
pub(crate) fn integrate_poses_into(
    model: &Model,
    nodes: &[MeshNode],
    strains: &[(Vector3<f64>, Vector3<f64>)],
    out: &mut Vec<(Vector3<f64>, Matrix3<f64>)>,
) {
    integrate_poses_with(model, nodes, strains, out, Sums::World);
}

/// [`integrate_poses_into`] with the arithmetic of `sums`: with [`Sums::Body`] each
/// interval's rotation is exp(u h/2)^2, the half step's exponential (which the position
/// needs) squared, instead of a second exponential exp(u h): the same rotation to
/// rounding (docs/benchmarks.md, "A batch row (row15, 2026-12-06, seventh session)"),
/// its products taken column by column in lanes ([`lanes::integrate_body`]).
#[inline(always)]
fn integrate_poses_with(
    model: &Model,
    nodes: &[MeshNode],
    strains: &[(Vector3<f64>, Vector3<f64>)],
    out: &mut Vec<(Vector3<f64>, Matrix3<f64>)>,
    sums: Sums,
) {
    if sums == Sums::Body {
        lanes::integrate_body(model, nodes, strains, out);
        return;
    }
    let mut p = model.base_position();
    let mut R = model.robot.base_rotation;
    out.clear();
    out.push((p, R));
    for k in 0..nodes.len() - 1 {
        let h = nodes[k + 1].s - nodes[k].s;
        if h > 0.0 {
            let v = (strain(model, &nodes[k], &strains[k].0) + strain(model, &nodes[k + 1], &strains[k + 1].0)) * 0.5;
            let u = (strains[k].1 + strains[k + 1].1) * 0.5;
            let half = so3::exp(&(u * (h / 2.0)));
            p += R * half * v * h;
            R *= so3::exp(&(u * h));
        }
        out.push((p, R));
    }
}

/// The arithmetic of the rigid-equilibrium sweeps: the same sums to rounding, in two
/// orders (docs/benchmarks.md, "A batch row (row15, 2026-12-06, seventh session)").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Sums {
    /// The default guess's: each interval's rotation from one exponential (the half
    /// step's, squared), the tendons' pulls summed in the body frame.
    Body,
    /// The shooting cross-check's and the friction start's: two exponentials an interval,
    /// the pulls rotated to the world frame tendon by tendon (from a guess integrated with
    /// one exponential an interval, shooting's Newton failed on a displacement input of
    /// tests/actuation.rs: docs/benchmarks.md, "Guess, estimate and count").
    World,
}

/// Where Newton starts when no previous solution is given.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum InitialGuess {
    /// The rigid-equilibrium estimate ([`rigid_estimate`]): exact for tendon-only loading,
    /// linear beam theory for small loads.
    #[default]
    RigidEquilibrium,
    /// The unloaded (reference) shape with reference strains, as most shooting codes start.
    Unloaded,
}

/// The initial state at every mesh node.
pub fn initial(model: &Model, nodes: &[MeshNode], kind: InitialGuess) -> Vec<State> {
    match kind {
        InitialGuess::RigidEquilibrium => rigid_estimate(model, nodes),
        InitialGuess::Unloaded => {
            let strains = reference_strains(model, nodes);
            integrate_poses(model, nodes, &strains)
                .into_iter()
                .zip(nodes.iter().zip(strains))
                .map(|((p, R), (node, (v, u)))| State { s: node.s, p, R, v, u })
                .collect()
        }
    }
}

/// Node states of a previous solution on `mesh`, a warm start: its own node states when the
/// meshes are the same, else its interpolant, with left limits for the left node of a jump.
/// On a Kirchhoff rod the translational coordinate is made from the solution's internal
/// force (interpolated linearly between nodes).
pub fn interpolate(model: &Model, guess: &Solution, mesh: &Mesh) -> Vec<State> {
    interpolate_nodes(model, &guess.nodes, mesh)
}

/// As [`interpolate`], from a solution's `nodes` alone (what the dense evaluation reads).
pub(crate) fn interpolate_nodes(model: &Model, nodes: &[Node], mesh: &Mesh) -> Vec<State> {
    let same = nodes.len() == mesh.nodes.len() && nodes.iter().zip(&mesh.nodes).all(|(a, b)| a.s == b.s);
    // In a buffer the thread kept ([`spare`]): the states of a warm start or of the next
    // mesh's guess go back there when the solve is done with them.
    let mut states = spare::take(mesh.nodes.len());
    if same {
        states.extend(nodes.iter().map(Node::state));
    } else {
        states.extend((0..mesh.nodes.len()).map(|k| {
            let s = mesh.nodes[k].s;
            State {
                s,
                ..crate::solution::at_limit(nodes, s, is_left(mesh, k))
            }
        }));
    }
    if model.robot.rod_model == RodModel::Kirchhoff {
        for (k, x) in states.iter_mut().enumerate() {
            let n = if same {
                nodes[k].n
            } else {
                let (i, _) = crate::solution::interval(nodes, x.s, is_left(mesh, k));
                let (a, b) = (&nodes[i], &nodes[i + 1]);
                let t = (x.s - a.s) / (b.s - a.s);
                a.n * (1.0 - t) + b.n * t
            };
            let site = model.site_on(x.s, mesh.nodes[k].segment_end);
            x.v = model
                .strains_for_wrench(&site, &(x.R.transpose() * n), &Vector3::zeros())
                .0;
        }
    }
    states
}

/// Whether mesh node k is the left node of a jump (it takes the left limit).
fn is_left(mesh: &Mesh, k: usize) -> bool {
    k + 1 < mesh.nodes.len() && mesh.is_jump(k)
}

/// The reference strains (v*, u*) at every mesh node.
fn reference_strains(model: &Model, nodes: &[MeshNode]) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    let mut out = Vec::with_capacity(nodes.len());
    reference_strains_into(model, nodes, &mut out);
    out
}

/// [`reference_strains`] into `out` (cleared first), whose buffer a caller reuses.
fn reference_strains_into(model: &Model, nodes: &[MeshNode], out: &mut Vec<(Vector3<f64>, Vector3<f64>)>) {
    out.clear();
    out.extend(nodes.iter().map(|n| {
        let r = model.robot.rod.reference_on(n.s, n.segment_end);
        (r.v_star, r.u_star)
    }));
}

/// Most shape sweeps of the rigid-equilibrium estimate (each costs one pass over the mesh).
const MAX_SWEEPS: usize = 40;
/// The sweeps stop when each strain group's change (v; u L) is below this absolute floor
/// or below [`RELATIVE_CHANGE`] of that group's deformation ([`settled`]): 1e-6 of a
/// radian over the rod is far below what Newton needs from a guess.
const ABSOLUTE_CHANGE: f64 = 1e-6;
/// The relative part of the stopping test ([`settled`]).
const RELATIVE_CHANGE: f64 = 1e-5;
/// Weight of the first sweep's step in the relaxed update (Aitken adapts it afterwards).
const RELAXATION: f64 = 0.5;

/// The rigid-equilibrium estimate of the state at every mesh node, refined by re-summing
/// the loads on the shape it predicts (moment arms and body frames from the previous sweep)
/// until the curvature stops changing, or grows (then the previous sweep is kept).
pub fn rigid_estimate(model: &Model, nodes: &[MeshNode]) -> Vec<State> {
    rigid_estimate_to(model, nodes, RELATIVE_CHANGE, Sums::Body)
}

/// [`initial`], with the rigid-equilibrium sweeps held to the absolute stopping test
/// alone (each strain group's change below 1e-6, [`settled`] without its relative part):
/// the shooting cross-check starts from this guess's base strains, and its Newton did not
/// converge on a pull-in of two antagonistic pairs (tests/shooting_displacement.rs) from
/// the guess that stops at 1e-5 of the deformation.
pub(crate) fn initial_absolute(model: &Model, nodes: &[MeshNode], kind: InitialGuess) -> Vec<State> {
    match kind {
        InitialGuess::RigidEquilibrium => rigid_estimate_to(model, nodes, 0.0, Sums::World),
        InitialGuess::Unloaded => initial(model, nodes, kind),
    }
}

/// [`rigid_estimate`] with the relative part `relative` of the stopping test ([`settled`])
/// and the arithmetic `sums`.
fn rigid_estimate_to(model: &Model, nodes: &[MeshNode], relative: f64, sums: Sums) -> Vec<State> {
    // The sweeps' buffers come from this thread's last estimate (taken out, so that an
    // estimate nested in a user function's call finds none and allocates its own).
    let mut buffers = SWEEP_BUFFERS.with(|b| std::mem::take(&mut *b.borrow_mut()));
    let x = rigid_estimate_fast(model, nodes, &mut buffers, relative, sums);
    SWEEP_BUFFERS.with(|b| *b.borrow_mut() = buffers);
    x
}

/// The buffers of [`rigid_estimate`]'s sweeps, kept per thread between estimates.
#[derive(Default)]
struct SweepBuffers {
    /// The node strains (v, u) of the current sweep and of the next.
    strains: Vec<(Vector3<f64>, Vector3<f64>)>,
    next: Vec<(Vector3<f64>, Vector3<f64>)>,
    /// The poses integrated from `strains`.
    shape: Vec<(Vector3<f64>, Matrix3<f64>)>,
    /// The distal wrenches of a sweep.
    wrench: Vec<(Vector3<f64>, Vector3<f64>)>,
    /// The fixed-point step and the one before it, flattened.
    step: Vec<f64>,
    last_step: Vec<f64>,
    /// The nodes' sites.
    sites: Vec<Site>,
    /// The taut tendons of every node's segment with their routing points there, as
    /// [`Model::tendons`] yields them, node after node, and where each node's end.
    routes: Vec<(usize, f64, RoutingPoint)>,
    route_ends: Vec<usize>,
}

thread_local! {
    /// The sweep buffers of this thread's last [`rigid_estimate`].
    static SWEEP_BUFFERS: std::cell::RefCell<SweepBuffers> = const {
        std::cell::RefCell::new(SweepBuffers {
            strains: Vec::new(),
            next: Vec::new(),
            shape: Vec::new(),
            wrench: Vec::new(),
            step: Vec::new(),
            last_step: Vec::new(),
            sites: Vec::new(),
            routes: Vec::new(),
            route_ends: Vec::new(),
        })
    };
}

/// [`rigid_estimate_in`], compiled for AVX2 and FMA on a processor that has them (checked
/// at run time): the same operations in the same order (Rust does not contract a product
/// and a sum into an FMA), so the same bits (docs/benchmarks.md, "Default solve cost
/// (row16, 2026-12-07, eighth session)").
fn rigid_estimate_fast(
    model: &Model,
    nodes: &[MeshNode],
    b: &mut SweepBuffers,
    relative: f64,
    sums: Sums,
) -> Vec<State> {
    avx2_fma!(rigid_estimate_in(model, nodes, b, relative, sums))
}

/// [`rigid_estimate_to`] in the buffers `b` (their contents on entry are not read).
#[inline(always)]
fn rigid_estimate_in(model: &Model, nodes: &[MeshNode], b: &mut SweepBuffers, relative: f64, sums: Sums) -> Vec<State> {
    let length = model.robot.length();
    let SweepBuffers {
        strains,
        next,
        shape,
        wrench,
        step,
        last_step,
        sites,
        routes,
        route_ends,
    } = b;
    reference_strains_into(model, nodes, strains);
    integrate_poses_with(model, nodes, strains, shape, sums);
    let mut last_change = f64::INFINITY;
    let mut relaxation = RELAXATION;
    let mut stepped = false;
    // The nodes' sites do not depend on the shape: evaluated once, not three times a sweep.
    sites.clear();
    sites.extend(nodes.iter().map(|n| model.site_on(n.s, n.segment_end)));
    // So do the tendons' routing points at the nodes: evaluated once, not once a sweep.
    // Room for every tendon at every node, so that a kept buffer does not grow when a later
    // solve has more taut tendons (a batch row allocates only its Solution).
    routes.clear();
    routes.reserve(nodes.len() * model.robot.tendons.len());
    route_ends.clear();
    for n in nodes {
        // Pushed one by one, in this kernel (`extend` was a baseline call).
        for route in model.tendons(n.s, Which::ActiveTo(n.segment_end)) {
            routes.push(route);
        }
        route_ends.push(routes.len());
    }
    // The deformation of each strain group, v and u L: the first sweep's step (from the
    // reference strains).
    let mut deformation = [0.0; 2];
    for _ in 0..MAX_SWEEPS {
        let pulls = Pulls::Kept(routes, route_ends, sums);
        sweep(model, (nodes, sites), (shape, strains), pulls, (wrench, next));
        // The fixed-point step, flattened (v then u L per node, so all are comparable), the
        // largest change of each group (v, u L) and, after the first step, Aitken's sums
        // against the step before, in one pass.
        let against = if stepped { Some(&last_step[..]) } else { None };
        let (groups, sums_aitken) = step_of(next, strains, length, against, step);
        let change = groups[0].max(groups[1]);
        if !(change < last_change || last_change.is_infinite()) || !change.is_finite() {
            break;
        }
        if !stepped {
            deformation = groups;
        }
        // Aitken's dynamic relaxation (Irons & Tuck): the plain fixed point can cycle when
        // a load's moment arm swings with the shape it bends (a tendon and a tip load
        // pulling the same way); the factor adapts to the observed contraction.
        if let Some((num, den)) = sums_aitken {
            relaxation = aitken_factor(relaxation, num, den);
        }
        relax_strains(strains, step, relaxation, length);
        integrate_poses_with(model, nodes, strains, shape, sums);
        last_change = change;
        std::mem::swap(step, last_step);
        stepped = true;
        if settled(groups, deformation, relative) {
            break;
        }
    }
    let mut x = spare::take(nodes.len());
    x.extend(
        shape
            .iter()
            .zip(nodes.iter().zip(strains.iter()))
            .map(|(&(p, R), (node, &(v, u)))| State { s: node.s, p, R, v, u }),
    );
    x
}

/// Whether the rigid-equilibrium sweeps have settled after a fixed-point step whose
/// largest change in each strain group, v and u L, is `change`: each group's is below
/// [`ABSOLUTE_CHANGE`] or below `relative` ([`RELATIVE_CHANGE`] by default) times the
/// group's `deformation` (the first sweep's change from the reference strains). Per group,
/// so that the small axial and shear strains of a stiff rod are held to the absolute floor,
/// not to the curvature's scale (docs/numerics.md, "Initial guess").
fn settled(change: [f64; 2], deformation: [f64; 2], relative: f64) -> bool {
    change
        .iter()
        .zip(deformation)
        .all(|(c, d)| *c < ABSOLUTE_CHANGE.max(relative * d))
}

/// The tendons that reach each node's segment ([`Model::reaching`], slack ones included)
/// with their routing points there, node after node into `routes`, and where each node's
/// end into `ends`: what [`distal_strains`] pulls with, kept across its sweeps since they
/// do not depend on the shape or the tensions.
pub(crate) fn reaching_routes(
    model: &Model,
    nodes: &[MeshNode],
    (routes, ends): (&mut Vec<(usize, f64, RoutingPoint)>, &mut Vec<usize>),
) {
    routes.clear();
    ends.clear();
    for n in nodes {
        routes.extend(model.reaching(n.s, Which::ActiveTo(n.segment_end)));
        ends.push(routes.len());
    }
}

/// The node strains that carry the loads distal to each node on the shape of the states
/// `x` (the sweep of [`rigid_estimate`]; `sites`: the nodes' sites; `routes`: the tendons
/// reaching each node, [`reaching_routes`]), with every tendon's tension at node k taken
/// from `tensions[k]` instead of the model's: a tension that varies along a tendon
/// (friction, docs/friction.md section 3) pulls each cross-section with its local value.
/// Into `out`; `wrench` is the buffer of the distal wrenches.
#[allow(clippy::type_complexity)]
#[inline(always)]
pub(crate) fn distal_strains(
    model: &Model,
    (nodes, sites): (&[MeshNode], &[Site]),
    routes: (&[(usize, f64, RoutingPoint)], &[usize]),
    x: &[State],
    tensions: &[Vec<f64>],
    (wrench, out): (
        &mut Vec<(Vector3<f64>, Vector3<f64>)>,
        &mut Vec<(Vector3<f64>, Vector3<f64>)>,
    ),
) {
    let shape: Vec<_> = x.iter().map(|s| (s.p, s.R)).collect();
    let strains: Vec<_> = x.iter().map(|s| (s.v, s.u)).collect();
    sweep(
        model,
        (nodes, sites),
        (&shape, &strains),
        Pulls::Local(routes.0, routes.1, tensions),
        (wrench, out),
    );
}

/// Aitken's dynamic relaxation factor (Irons & Tuck) after the fixed-point steps
/// `last_step` and `step`: the factor that would have cancelled the change between them
/// along `last_step`, kept in [0.1, 1]; `relaxation` (the last factor) when they are equal.
pub(crate) fn aitken(relaxation: f64, last_step: &[f64], step: &[f64]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    aitken_sums(last_step, step, (&mut num, &mut den));
    aitken_factor(relaxation, num, den)
}

/// Adds [`aitken`]'s sums over the steps `last` (a) and `step` (b) to `num` (a (b - a))
/// and `den` ((b - a)^2), entry by entry in order.
#[inline(always)]
fn aitken_sums(last: &[f64], step: &[f64], (num, den): (&mut f64, &mut f64)) {
    for (a, b) in last.iter().zip(step) {
        *num += a * (b - a);
        *den += (b - a) * (b - a);
    }
}

/// [`aitken`]'s factor from its sums `num` = sum a (b - a) and `den` = sum (b - a)^2 over
/// the steps a (the last) and b.
#[inline(always)]
fn aitken_factor(relaxation: f64, num: f64, den: f64) -> f64 {
    if den > 0.0 {
        (-relaxation * num / den).clamp(0.1, 1.0)
    } else {
        relaxation
    }
}

/// The fixed-point step from `strains` to `next`, flattened into `step` (v, then u L per
/// node; `length` is L), with the largest absolute change of each group (v, u L) and, when
/// `last_step` is given, [`aitken`]'s sums (num, den) against it: the same operations in
/// the same order as flattening, folding the groups and summing apart, in one pass.
#[inline(always)]
fn step_of(
    next: &[(Vector3<f64>, Vector3<f64>)],
    strains: &[(Vector3<f64>, Vector3<f64>)],
    length: f64,
    last_step: Option<&[f64]>,
    step: &mut Vec<f64>,
) -> ([f64; 2], Option<(f64, f64)>) {
    step.clear();
    step.resize(6 * strains.len(), 0.0);
    let mut groups = [0.0f64; 2];
    let (mut num, mut den) = (0.0, 0.0);
    for (k, ((a, b), out)) in next.iter().zip(strains).zip(step.chunks_exact_mut(6)).enumerate() {
        let (dv, du) = (a.0 - b.0, (a.1 - b.1) * length);
        let x = [dv[0], dv[1], dv[2], du[0], du[1], du[2]];
        out.copy_from_slice(&x);
        for (i, x) in x.iter().enumerate() {
            groups[i / 3] = groups[i / 3].max(x.abs());
        }
        if let Some(last) = last_step {
            aitken_sums(&last[6 * k..6 * k + 6], &x, (&mut num, &mut den));
        }
    }
    (groups, last_step.map(|_| (num, den)))
}

/// Moves the node strains (v, u) by `relaxation` times the flattened fixed-point `step`
/// (v, then u L per node; `length` is L).
pub(crate) fn relax_strains(strains: &mut [(Vector3<f64>, Vector3<f64>)], step: &[f64], relaxation: f64, length: f64) {
    for (k, s) in strains.iter_mut().enumerate() {
        for i in 0..3 {
            s.0[i] += relaxation * step[6 * k + i];
            s.1[i] += relaxation * step[6 * k + 3 + i] / length;
        }
    }
}

/// The tendons a sweep pulls each node with.
#[derive(Clone, Copy)]
enum Pulls<'a> {
    /// The model's tensions, with the taut tendons and their routing points at every node
    /// kept (`routes`, node after node; `ends[k]` ends node k's), summed as [`Sums`] says.
    Kept(&'a [(usize, f64, RoutingPoint)], &'a [usize], Sums),
    /// Every tendon's tension at node k from `tensions[k]` (friction), with the tendons
    /// reaching every node and their routing points there kept as in `Kept` (slack ones
    /// included: a tendon pulls where its local tension is positive, as
    /// [`Model::tendons`] takes it).
    Local(&'a [(usize, f64, RoutingPoint)], &'a [usize], &'a [Vec<f64>]),
}

/// One sweep: node strains carrying the loads distal to each node, summed on `shape`
/// (`sites`: the nodes' sites; `strains`: the node coordinates the tendons' paths are
/// taken from), into `out`, with the tendons of `pulls`; `wrench` is the buffer of the
/// distal wrenches.
#[allow(clippy::type_complexity)]
#[inline(always)]
fn sweep(
    model: &Model,
    (nodes, sites): (&[MeshNode], &[Site]),
    (shape, strains): (&[(Vector3<f64>, Matrix3<f64>)], &[(Vector3<f64>, Vector3<f64>)]),
    pulls: Pulls,
    (wrench, out): (
        &mut Vec<(Vector3<f64>, Vector3<f64>)>,
        &mut Vec<(Vector3<f64>, Vector3<f64>)>,
    ),
) {
    let last = nodes.len() - 1;
    // Distal load sums (N, M about p_k) by a backward sweep with the trapezoid rule.
    wrench.clear();
    wrench.resize(nodes.len(), (Vector3::zeros(), Vector3::zeros()));
    wrench[last] = model.point_wrench(nodes[last].s);
    for k in (0..last).rev() {
        let (N, M) = wrench[k + 1];
        let h = nodes[k + 1].s - nodes[k].s;
        wrench[k] = if h == 0.0 {
            let (f, l) = model.point_wrench(nodes[k].s);
            (N + f, M + l)
        } else {
            let (a, b) = (&sites[k], &sites[k + 1]);
            let d = shape[k + 1].0 - shape[k].0;
            (
                N + (a.f_e + b.f_e) * (h / 2.0),
                M + d.cross(&N) + (d.cross(&b.f_e) + a.l_e + b.l_e) * (h / 2.0),
            )
        };
    }
    out.clear();
    for (k, node) in nodes.iter().enumerate() {
        let site = &sites[k];
        let R = shape[k].1;
        let (v, u) = strains[k];
        let (mut n, mut m) = wrench[k];
        // The tendons loading this node's segment pull it back along their paths.
        let v = site.strain(&v);
        let pull = match pulls {
            Pulls::Kept(routes, ends, sums) => {
                let from = if k == 0 { 0 } else { ends[k - 1] };
                let tendons = routes[from..ends[k]].iter().copied();
                if sums == Sums::Body {
                    // n_b = R^T n - sum f_b: the pulls stay in the body frame.
                    let (mut n_b, mut m_b) = (R.transpose() * n, R.transpose() * m);
                    if let Ok((f, l)) = model.tendon_pull_body_of(tendons, node.s, &v, &u) {
                        n_b -= f;
                        m_b -= l;
                    }
                    out.push(model.strains_for_wrench(site, &n_b, &m_b));
                    continue;
                }
                model.tendon_pull_of(tendons, node.s, &R, &v, &u)
            }
            Pulls::Local(routes, ends, t) => {
                let from = if k == 0 { 0 } else { ends[k - 1] };
                let (local, factor) = (&t[k], model.tension_factor);
                let tendons = routes[from..ends[k]].iter().filter_map(|&(i, _, rp)| {
                    let tension = local[i];
                    (tension > 0.0).then_some((i, tension * factor, rp))
                });
                model.tendon_pull_of(tendons, node.s, &R, &v, &u)
            }
        };
        if let Ok((f, l)) = pull {
            n -= f;
            m -= l;
        }
        out.push(model.strains_for_wrench(site, &(R.transpose() * n), &(R.transpose() * m)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sweep with local tensions pulls with the kept routing points of the tendons
    /// reaching each node ([`reaching_routes`]) exactly as the model's own tendons would:
    /// with every node's tensions the model's (tendon 1 slack, tendon 2 pulling at half the
    /// helix's tension), it is the sweep with the model's tendons and routing points, bit
    /// for bit, on case H (the friction start relies on it, docs/friction.md section 3).
    #[test]
    fn local_sweep_pulls_as_the_model() {
        let robot = crate::cases::case_h();
        let mut model = Model::new(&robot);
        model.tensions[0] = 0.0;
        model.tensions[1] = 0.5 * model.tensions[4];
        let mesh = Mesh::uniform(&robot, 24).expect("mesh");
        let nodes = &mesh.nodes;
        let x = rigid_estimate(&model, nodes);
        let sites: Vec<Site> = nodes.iter().map(|n| model.site_on(n.s, n.segment_end)).collect();
        let (mut reaching, mut ends) = (Vec::new(), Vec::new());
        reaching_routes(&model, nodes, (&mut reaching, &mut ends));
        let tensions = vec![model.tensions.clone(); nodes.len()];
        let (mut wrench, mut local) = (Vec::new(), Vec::new());
        let routes = (&reaching[..], &ends[..]);
        distal_strains(
            &model,
            (nodes, &sites),
            routes,
            &x,
            &tensions,
            (&mut wrench, &mut local),
        );
        let (mut taut, mut taut_ends) = (Vec::new(), Vec::new());
        for n in nodes {
            taut.extend(model.tendons(n.s, Which::ActiveTo(n.segment_end)));
            taut_ends.push(taut.len());
        }
        let shape: Vec<_> = x.iter().map(|s| (s.p, s.R)).collect();
        let strains: Vec<_> = x.iter().map(|s| (s.v, s.u)).collect();
        let mut kept = Vec::new();
        let pulls = Pulls::Kept(&taut, &taut_ends, Sums::World);
        sweep(
            &model,
            (nodes, &sites),
            (&shape, &strains),
            pulls,
            (&mut wrench, &mut kept),
        );
        // The slack tendon is among the kept routes but pulls nowhere.
        assert!(reaching.len() > taut.len(), "a slack tendon is kept");
        assert_eq!(local, kept);
    }

    /// The stopping test of the rigid-equilibrium sweeps holds each strain group to its own
    /// scale: a change of 5e-6 in u L is small against a curvature deformation of 1 rad
    /// over the rod (below 1e-5 of it), but a change of 2e-6 in v is not small against the
    /// axial strain 1e-5 of a stiff rod, which stays held to the absolute floor of 1e-6.
    #[test]
    fn the_guess_stops_per_strain_group() {
        let bent = [1e-5, 1.0];
        // u L: 5e-6 < 1e-5 x 1 (relative); v: 5e-7 < 1e-6 (absolute).
        assert!(settled([5e-7, 5e-6], bent, RELATIVE_CHANGE));
        // v: 2e-6 is neither below 1e-6 nor below 1e-5 x 1e-5.
        assert!(!settled([2e-6, 5e-6], bent, RELATIVE_CHANGE));
        // u L: 2e-5 is above 1e-5 of the curvature's deformation.
        assert!(!settled([5e-7, 2e-5], bent, RELATIVE_CHANGE));
        // An unbent rod is held to the absolute floor in both groups, as before.
        assert!(!settled([5e-7, 5e-6], [0.0, 0.0], RELATIVE_CHANGE));
        assert!(settled([5e-7, 5e-7], [0.0, 0.0], RELATIVE_CHANGE));
        // Without the relative part (shooting's guess) only the absolute floor stops.
        assert!(!settled([5e-7, 5e-6], bent, 0.0));
        assert!(settled([5e-7, 5e-7], bent, 0.0));
    }

    /// The AVX2 build of the rigid-equilibrium sweeps, with the tendons' pulls and the
    /// exponentials compiled into it, gives the baseline build's bits (every node state) on
    /// the prototype with four tendons pulled (coupled and point-moment tendons) and on case
    /// H (a tip force and a helical tendon), with both sums and stopping tests, on 16
    /// intervals and on 1 (rotations above the exponential's series switch); on a processor
    /// without AVX2 both are the baseline.
    #[test]
    fn the_guess_gives_the_baseline_bits() {
        let bits = |x: &[State]| {
            x.iter()
                .flat_map(|n| {
                    n.p.iter()
                        .chain(n.R.iter())
                        .chain(n.v.iter())
                        .chain(n.u.iter())
                        .copied()
                })
                .map(f64::to_bits)
                .collect::<Vec<_>>()
        };
        let mut pulled = crate::cases::prototype();
        for (i, tendon) in pulled.tendons.iter_mut().enumerate().take(4) {
            tendon.set_tension(0.4 + 0.7 * i as f64);
        }
        let mut point_moment = pulled.clone();
        point_moment.tendon_model = crate::model::robot::TendonModel::PointMoment;
        // The largest rotation of a half interval (the exponential's argument) met.
        let mut largest_half_turn = 0.0f64;
        for robot in [pulled, point_moment, crate::cases::case_h()] {
            let model = Model::new(&robot);
            for intervals in [16, 1] {
                let mesh = Mesh::uniform(&robot, intervals).unwrap();
                for (relative, sums) in [(RELATIVE_CHANGE, Sums::Body), (0.0, Sums::World)] {
                    let nodes = &mesh.nodes;
                    let fast = rigid_estimate_fast(&model, nodes, &mut SweepBuffers::default(), relative, sums);
                    let baseline = rigid_estimate_in(&model, nodes, &mut SweepBuffers::default(), relative, sums);
                    assert_eq!(bits(&fast), bits(&baseline));
                    // A bent shape: the sweeps ran.
                    assert!(fast.last().unwrap().u.norm() > 1.0);
                    for (a, b) in fast.iter().zip(&fast[1..]) {
                        largest_half_turn = largest_half_turn.max(((a.u + b.u) * ((b.s - a.s) / 4.0)).norm());
                    }
                }
            }
        }
        // Above |theta| = 1/2 the exponential takes its closed form, not its series.
        assert!(largest_half_turn > 0.5, "{largest_half_turn}");
    }
}
