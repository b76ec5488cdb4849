//! Where Newton with friction starts (docs/friction.md section 3, "The start"): the
//! frictionless solution, or on the direct route the initial guess (the frictionless
//! rigid-equilibrium sweep), corrected for the tension profile by the rigid-equilibrium
//! sweep with the local tensions.
//!
//! A cut through the backbone and its tendons at s leaves on the distal part only the
//! external loads and the tendons' tensions at the cut, whatever the friction in the
//! channels beyond it; so the backbone's internal wrench at s is the distal external
//! wrench minus the tendons' pull `tau_i(s) t_i(s)` at s with their local tensions. The
//! start takes the frictionless solution, marches the capstan law along its shape for the
//! log tensions ([`march`]), and moves its strains by the change of that wrench (the sweep
//! of [`crate::mesh::guess`] with the local tensions, minus the same sweep with the
//! constant ones, both on the frictionless shape), its poses by the change of their
//! integral; then repeats on the new shape, since the turning the tension falls over
//! depends on the shape.
#![allow(non_snake_case)]

use super::Profile;
use crate::mesh::Mesh;
use crate::mesh::guess::{
    aitken, distal_strains, integrate_poses, integrate_poses_into, reaching_routes, relax_strains,
};
use crate::model::equations::{Model, Site};
use crate::model::routing::RoutingPoint;
use crate::simd::avx2_fma;
use crate::solution::State;
use nalgebra::{Matrix3, Vector3};

/// Most passes of the start. Each pass's shape change moves the turning, hence the log
/// tensions, by about mu times the change of the bending angle, and the tip load's moment
/// arm with it; relaxed, the passes settle in 4 (S) to 8 (H) at mu = 0.1 (docs/friction.md
/// section 3), each costing about a tenth of a residual evaluation with friction.
const PASSES: usize = 10;

/// A pass that changes the strains by less than this (scaled: v, and u L) is the last, from
/// a frictionless solution ([`Settle::Solution`]): a start that far from the solution leaves
/// Newton's first step about 3e-6 (its quadratic constant is about 3 in these units), which
/// chord steps finish, so further passes would not save Newton a step (on case H at mu =
/// 0.1 they did not: 1 Newton and 1 chord step after 6 passes as after 8, docs/benchmarks.md
/// "fs24"), and the start's own error (the turning between nodes as the angle between their
/// tangents, the sweep's midpoint rule) is 1e-5 to 1e-4 anyway.
const SETTLED: f64 = 1e-3;

/// [`SETTLED`] from the initial guess ([`Settle::Guess`], the direct route) and in the
/// continuation in the friction coefficients: 1e-4, as before 2026-12-07 (fs24). The load
/// histories start from rest on the direct route, and a looser start moved a rounding-level
/// choice there (tests/history.rs, `a_first_step_pulls_in_from_rest_a_tendon_the_rods_weight_stretches`:
/// the first step's inflection node was not placed); on S the passes end after the same
/// pass at either threshold, so this costs S nothing.
const SETTLED_GUESS: f64 = 1e-4;

/// What the start moves, which sets where its passes stop.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum Settle {
    /// A frictionless solution (the frictionless start of a solve with friction): [`SETTLED`].
    Solution,
    /// The initial guess (the direct route), or the continuation's states: [`SETTLED_GUESS`].
    Guess,
}

/// Log tensions of `profile` marched along the states `x` by the capstan law
/// `z' = w mu |t'|`: the turning of tendon j's path between two nodes is the angle between
/// its unit tangents there (second order in the node spacing; the solve's capstan rows
/// then correct it to order 4). An unloaded tendon keeps z = 0, as its capstan rows do.
/// `sites` are the nodes' sites, `routes[j]` slip j's routing at the nodes of its span.
#[inline(always)]
fn march(model: &Model, (sites, routes): (&[Site], &[Vec<RoutingPoint>]), x: &[State], profile: &mut Profile) {
    for (j, route) in routes.iter().enumerate() {
        let tendon = &model.robot.tendons[profile.slipping[j]];
        let slope = tendon
            .active_friction()
            .map_or(0.0, |f| f.motion.sign() * f.coefficient);
        let loaded = profile.base[j] > 0.0;
        let tangent = |k: usize| {
            let rp = &route[k];
            (x[k].R * (x[k].u.cross(&rp.r) + rp.r_s + sites[k].strain(&x[k].v))).normalize()
        };
        let mut z = 0.0;
        let mut last = tangent(0);
        profile.z[j][0] = 0.0;
        for k in 1..profile.z[j].len() {
            if k < route.len() {
                let next = tangent(k);
                if loaded {
                    z += slope * last.cross(&next).norm().atan2(last.dot(&next));
                }
                last = next;
            }
            profile.z[j][k] = z;
        }
    }
}

/// The slips' tensions at every node from `profile` into `out` (every tendon's tension
/// at each node, the others' the model's, which `out` holds already and keeps).
#[inline(always)]
fn node_tensions(profile: &Profile, out: &mut [Vec<f64>]) {
    for (n, t) in out.iter_mut().enumerate() {
        for (j, &i) in profile.slipping.iter().enumerate() {
            t[i] = profile.tension(j, profile.z[j][n.min(profile.spans[j])]);
        }
    }
}

/// Moves the frictionless solution or initial guess `x` (on `mesh`) to the start of Newton
/// with friction and writes the log tensions marched along it into `profile` (module
/// docs). The passes are relaxed as the rigid-equilibrium estimate's sweeps are (Aitken's
/// factor: the tip load's moment arm swings with the shape the tension profile bends) and
/// stop when a pass changes the strains less than [`SETTLED`] (from the guess
/// [`SETTLED_GUESS`]), or not less than the one
/// before did (then the shape before it is kept).
///
/// On x86-64 with AVX2 and FMA (checked at run time) compiled for them, with the sweeps, the
/// pose integration and the march inlined: the same operations in the same order (Rust
/// fuses no product and sum into an FMA), so the same bits.
pub(super) fn capstan_start(model: &Model, mesh: &Mesh, x: &mut [State], profile: &mut Profile, settle: Settle) {
    avx2_fma!(capstan_start_in(model, mesh, x, profile, settle))
}

/// [`capstan_start`]'s operations.
#[inline(always)]
fn capstan_start_in(model: &Model, mesh: &Mesh, x: &mut [State], profile: &mut Profile, settle: Settle) {
    let settled = match settle {
        Settle::Solution => SETTLED,
        Settle::Guess => SETTLED_GUESS,
    };
    let nodes = &mesh.nodes;
    let length = model.robot.length();
    let sites: Vec<Site> = nodes.iter().map(|n| model.site_on(n.s, n.segment_end)).collect();
    // The tendons reaching each node and their routing points there: the same on every pass.
    let (mut reaching, mut ends) = (Vec::new(), Vec::with_capacity(nodes.len()));
    reaching_routes(model, nodes, (&mut reaching, &mut ends));
    // Each slip's routing points at the nodes of its span: those of `reaching` (the same
    // evaluation, `Routing::at` at the node), else evaluated.
    let routes: Vec<Vec<RoutingPoint>> = (0..profile.count())
        .map(|j| {
            let tendon = profile.slipping[j];
            let routing = &model.robot.tendons[tendon].routing;
            (0..=profile.spans[j])
                .map(|k| {
                    let from = if k == 0 { 0 } else { ends[k - 1] };
                    reaching[from..ends[k]]
                        .iter()
                        .find(|r| r.0 == tendon)
                        .map_or_else(|| routing.at(nodes[k].s, length), |r| r.2)
                })
                .collect()
        })
        .collect();
    let x0 = x.to_vec();
    let mut tensions: Vec<Vec<f64>> = vec![model.tensions.clone(); nodes.len()];
    let (mut wrench, mut plain, mut rough) = (Vec::new(), Vec::new(), Vec::new());
    distal_strains(
        model,
        (nodes, &sites),
        (&reaching, &ends),
        &x0,
        &tensions,
        (&mut wrench, &mut plain),
    );
    let strains0: Vec<(Vector3<f64>, Vector3<f64>)> = x0.iter().map(|s| (s.v, s.u)).collect();
    let poses0 = integrate_poses(model, nodes, &strains0);
    // Each node's frame relative to its integrated pose, R_0 P_0^T: the same on every pass.
    let frames0: Vec<Matrix3<f64>> = x0.iter().zip(&poses0).map(|(s, a)| s.R * a.1.transpose()).collect();
    let mut strains = strains0.clone();
    let mut poses = Vec::with_capacity(nodes.len());
    let (mut last_change, mut relaxation) = (f64::INFINITY, 1.0f64);
    let (mut step, mut last_step) = (Vec::with_capacity(6 * nodes.len()), Vec::with_capacity(6 * nodes.len()));
    let mut kept = x.to_vec();
    for _ in 0..PASSES {
        march(model, (&sites, &routes), x, profile);
        node_tensions(profile, &mut tensions);
        distal_strains(
            model,
            (nodes, &sites),
            (&reaching, &ends),
            x,
            &tensions,
            (&mut wrench, &mut rough),
        );
        // The fixed-point step, flattened (v then u L per node, so all are comparable).
        step.clear();
        step.extend(
            strains
                .iter()
                .zip(strains0.iter().zip(rough.iter().zip(&plain)))
                .flat_map(|(s, (s0, (a, b)))| {
                    let (dv, du) = (s0.0 + (a.0 - b.0) - s.0, (s0.1 + (a.1 - b.1) - s.1) * length);
                    [dv[0], dv[1], dv[2], du[0], du[1], du[2]]
                }),
        );
        let change = step.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if !change.is_finite() || change >= last_change {
            x.copy_from_slice(&kept);
            break;
        }
        if !last_step.is_empty() {
            relaxation = aitken(relaxation, &last_step, &step);
        }
        relax_strains(&mut strains, &step, relaxation, length);
        integrate_poses_into(model, nodes, &strains, &mut poses);
        // The shape before this pass stays in `kept` (the buffers swapped, not copied).
        kept.swap_with_slice(x);
        for (k, state) in x.iter_mut().enumerate() {
            let (a, b) = (&poses0[k], &poses[k]);
            *state = State {
                s: kept[k].s,
                p: x0[k].p + (b.0 - a.0),
                R: frames0[k] * b.1,
                v: strains[k].0,
                u: strains[k].1,
            };
        }
        if change < settled {
            break;
        }
        last_change = change;
        std::mem::swap(&mut step, &mut last_step);
    }
    march(model, (&sites, &routes), x, profile);
}

#[cfg(test)]
mod tests {
    use super::super::{Capstan, Method, Options, Settings, SolveReport, System, Workspace, newton};
    use super::*;
    use crate::mesh::guess::interpolate;
    use crate::{Friction, Motion, Robot, cases};

    /// The largest scaled difference (p / L, v, u L, z) between the start and the converged
    /// solution with friction on the frictionless mesh, and the same for the frictionless
    /// solution with constant tensions (the start before this module).
    fn distances(robot: &Robot) -> (f64, f64) {
        let mut smooth = robot.clone();
        for t in &mut smooth.tendons {
            t.friction = None;
        }
        let first = crate::collocation::solve(&smooth, &Options::default()).expect("frictionless solve");
        let points: Vec<f64> = first.nodes.iter().map(|n| n.s).collect();
        let mesh = Mesh::from_points(robot, &points).expect("mesh");
        let model = Model::new(robot);
        let length = robot.length();
        let plain = interpolate(&model, &first, &mesh);
        let mut start = plain.clone();
        let mut profile = Profile::new(&model, &mesh);
        capstan_start(&model, &mesh, &mut start, &mut profile, Settle::Solution);
        let started = profile.z.clone();
        // Converged from the start, to rounding.
        let mut system = System::new(model.clone(), mesh.clone());
        system.friction = Some(profile);
        let mut ws = Workspace::new(&system, Default::default()).expect("workspace");
        let mut border = Capstan::new(system);
        let settings = Settings {
            tolerance: 1e-13,
            max_iterations: 20,
            reuse_factors: false,
            stop_when_damped: false,
        };
        let mut x = start.clone();
        let mut report = SolveReport::new(Method::Collocation);
        let (termination, _) = newton::run_bordered(&mut border, &mut ws, &mut x, &settings, &mut report);
        assert_eq!(termination, crate::report::Termination::Converged);
        border.load(super::super::Point::Current);
        let z = border.system.friction.as_ref().expect("profile").z.clone();
        let distance = |y: &[State], zy: &[Vec<f64>]| {
            let states = y.iter().zip(&x).flat_map(|(a, b)| {
                let (dp, dv, du) = ((a.p - b.p) / length, a.v - b.v, (a.u - b.u) * length);
                [dp.amax(), dv.amax(), du.amax()]
            });
            let logs = zy
                .iter()
                .zip(&z)
                .flat_map(|(a, b)| a.iter().zip(b).map(|(p, q)| (p - q).abs()));
            states.chain(logs).fold(0.0f64, f64::max)
        };
        let constant: Vec<Vec<f64>> = z.iter().map(|zj| vec![0.0; zj.len()]).collect();
        (distance(&start, &started), distance(&plain, &constant))
    }

    /// The start lies within Newton's one-step reach of the solution with friction, where the
    /// frictionless solution with constant tensions does not: S and H at mu = 0.1 in pull,
    /// and H in release.
    #[test]
    fn start_is_near_the_solution_with_friction() {
        for (robot, tendon, motion) in [
            (cases::case_s(), 0, Motion::Pull),
            (cases::case_h(), 4, Motion::Pull),
            (cases::case_h(), 4, Motion::Release),
        ] {
            let mut rough = robot.clone();
            rough.tendons[tendon].friction = Some(Friction {
                coefficient: 0.1,
                motion,
            });
            let (start, plain) = distances(&rough);
            eprintln!(
                "{motion:?} on tendon {}: start {start:e}, frictionless {plain:e}",
                tendon + 1
            );
            // Measured 1.1e-5 (S), 3.5e-4 (H pull), 1.8e-4 (H release) with the passes
            // stopped at [`SETTLED`] (5.6e-5 and 9.7e-5 on H at 1e-4: the start's own
            // error, turning between node tangents, midpoint poses); 1e-3 still leaves
            // Newton's first step about 3e-6 (quadratic constant about 3 in these units).
            assert!(start < 1e-3, "start {start:e} from the solution with friction");
            // The frictionless start is 0.18 (S) to 0.35 (H release) away: the start must
            // be far closer, or it has not moved.
            assert!(
                start < 0.05 * plain,
                "start {start:e} against the frictionless {plain:e}"
            );
        }
    }
}
