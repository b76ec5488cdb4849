//! Random full-slip solves of the prototype with friction on opposite tendons 1 and 3
//! (docs/friction.md, "refuse21"): the probe that found collocation refusing large-mu solves
//! the shooting solver answers, and the refused cases it found, kept as fast tests.
//!
//! The probe is ignored by default (a few minutes on a release build):
//! `cargo test --release --test friction_probe -- --ignored --nocapture`.

use nalgebra::Vector3;
use tdcr::{Friction, Motion, Robot, Rod, Routing, Tendon, cases, shooting};

/// Random inputs from a fixed linear congruential sequence, uniform in [0, 1).
fn uniform(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

/// The prototype with tendons 1 and 3 (indices 0 and 2) at `tensions`, friction `mu` on
/// each (tendon 1 released when `release`), and a tip moment `moment` N m about world y
/// (the horizontal normal of the plane the two tendons bend the rod in).
fn opposite(tensions: [f64; 2], mu: [f64; 2], release: bool, moment: f64) -> Robot {
    let mut robot = cases::prototype();
    robot.tendons[0].set_tension(tensions[0]);
    robot.tendons[2].set_tension(tensions[1]);
    let motion = if release { Motion::Release } else { Motion::Pull };
    robot.tendons[0].friction = Some(Friction {
        coefficient: mu[0],
        motion,
    });
    robot.tendons[2].friction = Some(Friction::pull(mu[1]));
    robot.loads.tip_moment = Vector3::new(0.0, moment, 0.0);
    robot
}

/// Case k of the probe's sequence: tensions 0 to 5 N (tendon 1 near slack, 0 to 0.05 N,
/// in every other case), mu 0.05 to 1 on each, tendon 1 released in 30 %, a tip moment of
/// up to 0.03 N m either way.
fn case(state: &mut u64, k: usize) -> Robot {
    let t1 = if k.is_multiple_of(2) {
        0.05 * uniform(state)
    } else {
        5.0 * uniform(state)
    };
    let t3 = 5.0 * uniform(state);
    let mu = [0.05 + 0.95 * uniform(state), 0.05 + 0.95 * uniform(state)];
    let release = uniform(state) < 0.3;
    let moment = 0.03 * (2.0 * uniform(state) - 1.0);
    opposite([t1, t3], mu, release, moment)
}

fn tight() -> shooting::Options {
    shooting::Options {
        integration_tolerance: 1e-12,
        ..Default::default()
    }
}

/// The distance between the tips of two solves (m).
fn apart(a: &tdcr::Solution, b: &tdcr::Solution) -> f64 {
    (a.tip_position() - b.tip_position()).norm()
}

/// The probe: `TDCR_PROBE_CASES` cases (default 450) of the sequence from seed 2026, each
/// solved at default settings. An answer is checked against a solve at tolerance 1e-10
/// (its true error; 1e-9 or 1e-8 where that refuses) and against the shooting solver at
/// 1e-12 where it answers; a refusal
/// is untrue where the shooting solver or collocation on a fixed mesh of 128 intervals
/// answers. Fails on an untrue refusal, an answer away from shooting, or an estimate below
/// the true error.
#[test]
#[ignore]
fn probe_opposite_tendons_with_large_friction() {
    let count: usize = std::env::var("TDCR_PROBE_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(450);
    // References of the true error: the first of three tight tolerances that answers (the
    // tightest can refuse where the mesh grows past what Newton reaches from the last one).
    let references: Vec<_> = [1e-10, 1e-9, 1e-8]
        .into_iter()
        .map(|tolerance| tdcr::collocation::Options {
            tolerance: Some(tolerance),
            ..Default::default()
        })
        .collect();
    let fixed = tdcr::collocation::Options {
        intervals: 128,
        tolerance: None,
        ..Default::default()
    };
    let mut state = 2026;
    let (mut refused, mut untrue, mut wrong) = (Vec::new(), Vec::new(), Vec::new());
    let (mut continued, mut worst_ratio, mut worst_shooting) = (0, 0.0_f64, 0.0_f64);
    for k in 0..count {
        let robot = case(&mut state, k);
        let describe = format!(
            "case {k}: tensions {:.4} {:.4} N, mu {:.3} {:.3}, tendon 1 {:?}, moment {:.4} N m",
            robot.tendons[0].tension(),
            robot.tendons[2].tension(),
            robot.tendons[0].friction.map_or(0.0, |f| f.coefficient),
            robot.tendons[2].friction.map_or(0.0, |f| f.coefficient),
            robot.tendons[0].friction.map(|f| f.motion),
            robot.loads.tip_moment.y
        );
        let shot = shooting::solve(&robot, &tight());
        match tdcr::solve(&robot, &Default::default()) {
            Ok(c) => {
                continued += usize::from(c.report.notes.iter().any(|n| n.contains("followed from 0")));
                let estimate = c.report.error_estimate.map_or(f64::NAN, |e| e.tip_position);
                let reference = references.iter().find_map(|o| tdcr::collocation::solve(&robot, o).ok());
                let (truth, bound) = reference.as_ref().map_or((f64::NAN, 0.0), |f| {
                    (
                        apart(&c, f),
                        f.report.error_estimate.map_or(f64::NAN, |e| e.tip_position),
                    )
                });
                worst_ratio = worst_ratio.max(truth / estimate);
                let from_shooting = shot.as_ref().map_or(0.0, |s| apart(&c, s));
                worst_shooting = worst_shooting.max(from_shooting);
                // Three times the estimate and the reference's: deferred correction's
                // estimate is asymptotically exact (1e-11 m for rounding). Three times the
                // estimate plus 1e-8 m from shooting: its own error at 1e-12 reaches 5e-9 m
                // on the steepest profiles (case 163 against the reference).
                if !(truth <= 3.0 * (estimate + bound) + 1e-11 && from_shooting <= 3.0 * estimate + 1e-8) {
                    eprintln!(
                        "{describe}: true error {truth:e} m, estimate {estimate:e} m, {from_shooting:e} m from \
                         shooting"
                    );
                    wrong.push(k);
                }
            }
            Err(e) => {
                let answered = shot.is_ok() || tdcr::collocation::solve(&robot, &fixed).is_ok();
                eprintln!("{describe}: refused ({e}); answered by shooting or on 128 intervals: {answered}");
                refused.push(k);
                if answered {
                    untrue.push(k);
                }
            }
        }
    }
    eprintln!(
        "{count} cases: {} refused {refused:?}, {} of them untrue {untrue:?}; {continued} answered by the \
         continuation in mu; worst true error over the estimate {worst_ratio:.3}, worst distance to \
         shooting {worst_shooting:.3e} m; {} wrong {wrong:?}",
        refused.len(),
        untrue.len(),
        wrong.len()
    );
    assert!(untrue.is_empty() && wrong.is_empty());
}

/// Two solves the probe found refused on main (cases 163 and 441: tendon 1 released at
/// about 4.5 N with mu 0.63 and 0.36, tendon 3 pulled with mu 0.43 and 0.91, opposite tip
/// moments): Newton with friction failed from the frictionless shape on the first mesh,
/// from the capstan start and from constant tensions. The continuation in the friction
/// coefficients answers them: the answer agrees with the shooting solver, and its estimate
/// covers its distance to a solve at tolerance 1e-10.
#[test]
fn large_friction_on_a_released_tendon_is_answered() {
    let cases = [
        opposite(
            [4.471881775438046, 0.6532878863777375],
            [0.6317954495919584, 0.42573848435693806],
            true,
            -0.023271778194689948,
        ),
        opposite(
            [4.755257850684195, 1.302669994482863],
            [0.35585877468993965, 0.9133981975411736],
            true,
            0.006960523398905223,
        ),
    ];
    let fine = tdcr::collocation::Options {
        tolerance: Some(1e-10),
        ..Default::default()
    };
    for robot in cases {
        let c = tdcr::solve(&robot, &Default::default()).unwrap();
        let estimate = c.report.error_estimate.unwrap().tip_position;
        assert!(
            c.report.notes.iter().any(|n| n.contains("followed from 0")),
            "{:?}",
            c.report.notes
        );
        let reference = tdcr::collocation::solve(&robot, &fine).unwrap();
        let truth = apart(&c, &reference);
        // Three times the estimate: deferred correction is asymptotically exact; 1e-11 m for
        // the reference's own error (its tolerance, 2.4e-11 m, is met with a factor ~10 to spare).
        assert!(
            truth <= 3.0 * estimate + 1e-11,
            "true error {truth:e} m, estimate {estimate:e} m"
        );
        // 1e-8 m: the shooting solver's own error at 1e-12 on these steep tension profiles
        // (5e-9 m on the first against the reference).
        let s = shooting::solve(&robot, &tight()).unwrap();
        assert!(apart(&c, &s) < 1e-8, "{:e} m from shooting", apart(&c, &s));
        assert!(
            apart(&reference, &s) < 1e-8,
            "{:e} m from shooting",
            apart(&reference, &s)
        );
    }
}

/// Case 91 of the probe (tendon 1 released at 2.19 N with mu 0.93) at tolerance 1e-9:
/// answered by the continuation on 32 intervals, whose estimate then asked for 3 752; Newton
/// failed there from the 32-interval answer interpolated (main refused the solve: the
/// "third mesh" of docs/friction.md's kinks20 probe). The mesh between them, 64 intervals, converges, and the
/// refinement goes on from it. The shooting solver breaks down on this robot (the
/// tangential friction loads), so the answer is checked against the solve at tolerance
/// 1e-8, which needs no mesh between.
#[test]
fn a_mesh_newton_fails_on_is_reached_through_a_halved_one() {
    let robot = opposite(
        [2.191613373984957, 3.304268274921852],
        [0.9301479208260797, 0.16785393348536815],
        true,
        0.01881651726173821,
    );
    let at = |tolerance: f64| {
        let options = tdcr::collocation::Options {
            tolerance: Some(tolerance),
            ..Default::default()
        };
        tdcr::collocation::solve(&robot, &options).unwrap()
    };
    let (tight, loose) = (at(1e-9), at(1e-8));
    // The path this test is about: the refinement went on from a halved mesh, and says so.
    assert!(
        tight.report.notes.iter().any(|n| n.contains("every interval halved")),
        "{:?}",
        tight.report.notes
    );
    let estimate = |s: &tdcr::Solution| s.report.error_estimate.unwrap().tip_position;
    assert!(estimate(&tight) <= 1e-9 * robot.length());
    // Three times both estimates: deferred correction is asymptotically exact; 1e-12 m for
    // rounding.
    let bound = 3.0 * (estimate(&tight) + estimate(&loose)) + 1e-12;
    assert!(
        apart(&tight, &loose) <= bound,
        "{:e} m apart, bound {bound:e} m",
        apart(&tight, &loose)
    );
}

/// Case 167 of the probe (tendon 1 released at 4.76 N with mu 0.895, tendon 3 pulled at
/// 4.01 N with mu 0.380): the continuation in the coefficients gives up near two thirds of
/// them (docs/friction.md section 4, "Large friction on a released tendon"). The refusal
/// reports that last run -- its termination, not the earlier run's at the full coefficients
/// -- and how far the coefficients got; it does not send the user to the shooting solver,
/// which breaks down on this robot.
#[test]
fn a_refusal_after_the_continuation_says_how_far_it_got() {
    let robot = opposite(
        [4.7587430601211675, 4.00565086861725],
        [0.8950880107773121, 0.37986643273817366],
        true,
        0.008960342660040147,
    );
    let error = tdcr::collocation::solve(&robot, &tdcr::collocation::Options::default()).unwrap_err();
    let message = error.to_string();
    assert!(
        message.contains("Newton solved 67 % of the friction coefficients"),
        "{message}"
    );
    // The branch past it (docs/friction.md, "fold22"): tendon 1's path degenerates.
    assert!(message.contains("ends there"), "{message}");
    assert!(!message.contains("shooting"), "{message}");
    match error {
        // The continuation's last run stalls in the line search (the history printed with
        // the error is that run's); the run at the full coefficients before it stopped at
        // the iteration limit, which the refusal used to report.
        tdcr::Error::NotConverged { report, .. } => {
            assert_eq!(report.termination, tdcr::Termination::LineSearchFailed)
        }
        other => panic!("{other}"),
    }
}

/// The fraction of the friction coefficients (per cent) and the delivered tension (N) a
/// refusal reports where the branch from the frictionless shape ends (docs/friction.md,
/// "fold22").
fn branch_end(message: &str) -> (f64, f64) {
    let number = |after: &str, until: &str| -> f64 {
        let start = message.find(after).map(|i| i + after.len()).unwrap();
        let end = start + message[start..].find(until).unwrap();
        message[start..end]
            .trim()
            .parse()
            .unwrap_or_else(|_| panic!("{message}"))
    };
    (
        number("arclength reaches ", " % of them"),
        number("and delivers ", " N"),
    )
}

/// One released tendon on a straight rod without other loads, where the branch has a closed
/// form (docs/friction.md, "fold22"): the rod's moment is tau(s) r, so its curvature
/// tau r / EI turns the tendon at that rate and tau' = lambda mu r tau^2 / EI, whence
/// 1/tau_0 - 1/tau(L) = lambda mu r L / EI. The tendon's path speed v_3 - kappa r (v_3 =
/// 1 - tau / EA) vanishes at the tip when tau(L) = tau_s = 1 / (r^2 / EI + 1 / EA): the branch
/// ends at lambda_s = (1/tau_0 - 1/tau_s) EI / (mu r L). The refusal reports it, on fixed
/// meshes of 64 and 128 intervals.
#[test]
fn a_refusal_reports_where_the_branch_ends() {
    let (tau0, mu) = (3.0, 1.0);
    let (length, radius, r) = (cases::LENGTH, cases::RADIUS, cases::TENDON_OFFSET);
    let mut robot = Robot::new(Rod::solid_circle(
        length,
        radius,
        cases::YOUNGS_MODULUS,
        cases::POISSON_RATIO,
    ))
    .with_tendon(Tendon::new(Routing::straight(r, 0.0), tau0));
    robot.tendons[0].friction = Some(Friction {
        coefficient: mu,
        motion: Motion::Release,
    });
    let area = std::f64::consts::PI * radius * radius;
    let (ei, ea) = (
        cases::YOUNGS_MODULUS * area * radius * radius / 4.0,
        cases::YOUNGS_MODULUS * area,
    );
    let tau_s = 1.0 / (r * r / ei + 1.0 / ea);
    let lambda_s = (1.0 / tau0 - 1.0 / tau_s) * ei / (mu * r * length);
    let mut errors = Vec::new();
    for intervals in [64, 128] {
        let error = tdcr::collocation::solve(&robot, &tdcr::collocation::Options::fixed(intervals)).unwrap_err();
        let message = error.to_string();
        assert!(
            message.contains("ends there") && message.contains("tendon 1"),
            "{message}"
        );
        let (percent, tension) = branch_end(&message);
        // The corrector stops where the path speed is about 1e-6: tau(L) within 1e-4 of
        // tau_s relative (dtau/dspeed ~ tau_s), printed to 1e-3 N.
        assert!(
            (tension - tau_s).abs() <= 2e-3 + 1e-4 * tau_s,
            "{tension} N, closed form {tau_s} N"
        );
        errors.push((percent / 100.0 - lambda_s).abs());
    }
    // The scheme is of order 4 (measured: 6.2e-3 on 64 intervals, 4e-4 on 128, 7.4e-2 on
    // the default first mesh of 32); 2e-3 on 128 intervals leaves a factor 5 to it, and
    // the finer mesh must be the closer (5e-5 for the printed 1e-4 of a per cent).
    assert!(errors[1] <= 2e-3, "lambda off by {errors:?}, closed form {lambda_s}");
    assert!(errors[1] < errors[0] + 5e-5, "{errors:?}");
}

/// A fold: one released tendon close to the axis (1 mm) on a straight rod, at 20 N, on a
/// fixed mesh of 16 intervals. In the continuum its delivered tension runs away as lambda
/// approaches lambda_inf = EI / (mu r L tau_0) = 0.872 (the closed form of
/// `a_refusal_reports_where_the_branch_ends`; its path would degenerate at 4 060 N, lambda
/// 0.868); on a coarse mesh the discrete capstan rows turn back first, at 91 N on 8
/// intervals, 138 N on 16 and 418 N on 32 (lambda 0.634, 0.714, 0.845). The fold is a
/// property of the robot on that mesh, not of how far its own coefficient lies past it: the
/// solve at a coefficient 0.1 % below the reported one answers, and 0.1 % above it is refused
/// with the same fold.
#[test]
fn a_refusal_reports_the_fold_it_finds() {
    let with = |mu: f64| {
        let mut robot = Robot::new(Rod::solid_circle(
            cases::LENGTH,
            cases::RADIUS,
            cases::YOUNGS_MODULUS,
            cases::POISSON_RATIO,
        ))
        .with_tendon(Tendon::new(Routing::straight(0.001, 0.0), 20.0));
        robot.tendons[0].friction = Some(Friction {
            coefficient: mu,
            motion: Motion::Release,
        });
        tdcr::collocation::solve(&robot, &tdcr::collocation::Options::fixed(16))
    };
    let folded = |mu: f64| {
        let message = with(mu).unwrap_err().to_string();
        assert!(message.contains("turns back there (a fold)"), "{message}");
        let (percent, tension) = branch_end(&message);
        (percent / 100.0 * mu, tension)
    };
    let (coefficient, tension) = folded(1.0);
    // The coefficient of the mesh's fold (measured 0.7135) and its tension (138 N).
    assert!((0.70..0.73).contains(&coefficient) && (120.0..160.0).contains(&tension));
    assert!(with(coefficient * 0.999).is_ok());
    let (again, tension_again) = folded(coefficient * 1.001);
    // The same fold to twice the printed resolution (lambda to 1e-2 of a per cent: 5e-5 of
    // the coefficient); the tension, which is not flat along the branch there, to where
    // regula falsi stops (0.05 N: 4e-4 of it).
    assert!(
        (again - coefficient).abs() <= 2e-6 + 1e-4 * coefficient,
        "{again} against {coefficient}"
    );
    assert!(
        (tension_again - tension).abs() <= 0.05,
        "{tension_again} N against {tension} N"
    );
}

/// Case 113 of the probe with tendon 1's coefficient lowered to 0.55 (below where its branch
/// ends on every mesh: 0.709 of the coefficient on the first mesh, 0.626 on 128 intervals;
/// docs/friction.md, "fold22"). The continuation in the coefficients gives up at 89 % of
/// them on the first mesh; the branch followed on by its arclength reaches them, and the
/// refinement goes on from that answer. Its estimate covers its distance to a solve at
/// tolerance 1e-10 (measured 1.08e-10 m against an estimate of 1.09e-10 m).
#[test]
fn past_the_continuation_the_branch_reaches_the_coefficients() {
    let robot = opposite([4.2340, 4.0224], [0.55, 0.866], true, 0.0066);
    let c = tdcr::solve(&robot, &Default::default()).unwrap();
    assert!(
        c.report
            .notes
            .iter()
            .any(|n| n.contains("branch of equilibria by its arclength")),
        "{:?}",
        c.report.notes
    );
    let fine = tdcr::collocation::Options {
        tolerance: Some(1e-10),
        ..Default::default()
    };
    let reference = tdcr::collocation::solve(&robot, &fine).unwrap();
    let estimate = c.report.error_estimate.unwrap().tip_position;
    let bound = reference.report.error_estimate.unwrap().tip_position;
    // Three times both estimates, as in the probe: deferred correction is asymptotically
    // exact; 1e-11 m for rounding.
    let truth = apart(&c, &reference);
    assert!(
        truth <= 3.0 * (estimate + bound) + 1e-11,
        "true error {truth:e} m, estimate {estimate:e} m"
    );
}

/// Case 251 of the probe (tendon 1 released at 4.20 N with mu 0.613, tendon 3 pulled at
/// 1.62 N with mu 0.139; docs/friction.md, "fold23"). The continuation in the coefficients
/// reaches them on the first mesh (32 intervals, tendon 1 delivering 63.1 N, estimate
/// 3.4e-3 m), but that answer is the coarse mesh's alone: Newton from it fails on the 1 305
/// intervals its estimate asks for and on the 64 of that mesh halved (no descent). On 64
/// intervals the branch from the frictionless shape ends before the coefficients, where
/// tendon 1's path degenerates. The refusal says so, on that mesh, and its advice holds:
/// the robot with its coefficients lowered to 90 % of their values (below where the branch
/// ends on 64 and 128 intervals, 95.76 % and 95.29 %) is answered.
#[test]
fn a_later_mesh_newton_fails_on_reports_where_the_branch_ends() {
    let robot = opposite(
        [4.195355500800999, 1.6243959856760033],
        [0.6131088909246815, 0.13890054080086875],
        true,
        -0.001159675640740101,
    );
    let message = tdcr::solve(&robot, &Default::default()).unwrap_err().to_string();
    assert!(
        message.contains("ends there")
            && message.contains("on 64 intervals, from the frictionless shape")
            && message.contains("tendon 1"),
        "{message}"
    );
    let (percent, tension) = branch_end(&message);
    // Where the branch ends on 64 intervals (measured 95.76 %, 66.943 N), within 0.5 % of the
    // coefficients of 128 intervals' 95.29 %; the tension where tendon 1's path degenerates
    // is about EI/r^2 = 66 N on every mesh (fold22's table: 64.9 to 67.9 N).
    assert!((95.29..96.3).contains(&percent), "{message}");
    assert!((64.0..69.0).contains(&tension), "{message}");
    let mut lowered = robot.clone();
    for t in &mut lowered.tendons {
        if let Some(f) = &mut t.friction {
            f.coefficient *= 0.9;
        }
    }
    let answer = tdcr::solve(&lowered, &Default::default()).unwrap();
    assert!(answer.report.tolerance_met.unwrap_or(false), "{:?}", answer.report);
}
