//! Calibration of the friction coefficient (docs/friction.md, docs/calibration.md) on
//! synthetic data: the prototype in the paper's frame with friction on tendon 1 (straight),
//! pulled through 1 to 4.91 N (loading steps, `pull`) and let back through 4 to 1 N
//! (unloading steps, `release`), with two tip loads; tips made by the model itself with a
//! known mu (and E), plus Gaussian noise of 0.1 mm per coordinate. The fit must recover the
//! truth within four of its own standard errors, alone and with E and the base angles.
//! Also the experiments CSV's motion column and the errors of a fit of mu without friction.

use nalgebra::Vector3;
use tdcr::cases::{GaussianNoise, prototype_in_paper_frame};
use tdcr::fit::calibration::{CalibrationOptions, Fit, Measurement, Parameters, calibrate, predict};
use tdcr::io::experiments::{parse_csv, to_csv};
use tdcr::{Error, Friction, Motion, Robot};

/// Measurement noise per coordinate of the tips (m): 0.1 mm, as in tests/calibration.rs.
const NOISE: f64 = 1e-4;

/// The prototype in the paper's frame with friction mu on tendon 1.
fn robot(mu: f64) -> Robot {
    let mut robot = prototype_in_paper_frame();
    robot.tendons[0].friction = Some(Friction::pull(mu));
    robot
}

/// Loading steps of tendon 1 (pull), unloading steps (release), and tip loads of 0.098 N
/// and 0.196 N (world -y of the paper's frame, across the bending plane) at 2.94 N.
fn experiments() -> Vec<Measurement> {
    let k = 5;
    let step = |tension: f64, tip: f64, motion| {
        let mut tensions = vec![0.0; k];
        tensions[0] = tension;
        Measurement {
            tensions,
            tip_force: Vector3::new(0.0, -tip, 0.0),
            measured_tip: Vector3::zeros(),
            motion: Some(motion),
        }
    };
    let mut out: Vec<Measurement> = [1.0, 2.0, 3.0, 4.0, 4.91]
        .iter()
        .map(|&t| step(t, 0.0, Motion::Pull))
        .collect();
    out.extend([4.0, 3.0, 2.0, 1.0].iter().map(|&t| step(t, 0.0, Motion::Release)));
    out.push(step(2.94, 0.098, Motion::Pull));
    out.push(step(2.94, 0.196, Motion::Release));
    out
}

/// The experiments with tips measured on `truth` plus NOISE per coordinate.
fn synthetic(robot: &Robot, truth: &Parameters, seed: u64) -> Vec<Measurement> {
    let mut experiments = experiments();
    let tips = predict(robot, truth, &experiments, &CalibrationOptions::default()).unwrap();
    let mut gauss = GaussianNoise::new(seed);
    for (e, tip) in experiments.iter_mut().zip(tips) {
        e.measured_tip = tip + NOISE * Vector3::new(gauss.next(), gauss.next(), gauss.next());
    }
    experiments
}

#[test]
fn loading_and_unloading_tips_recover_mu_within_its_standard_error() {
    // The start: mu = 0.05 and the nominal E; the truth: mu = 0.1, E 4 % stiffer.
    let start = robot(0.05);
    let mut truth = Parameters::of(&start);
    truth.friction = 0.1;
    truth.youngs_modulus *= 1.04;
    for (name, fit) in [
        (
            "mu",
            Fit {
                friction: true,
                ..Fit::none()
            },
        ),
        (
            "E, euler, mu",
            Fit {
                friction: true,
                ..Fit::default()
            },
        ),
    ] {
        let only_mu = !fit.youngs_modulus;
        let mut truth = truth;
        if only_mu {
            // E is not fitted, so the data are made with the start's.
            truth.youngs_modulus = Parameters::of(&start).youngs_modulus;
        }
        let data = synthetic(&start, &truth, 7);
        let options = CalibrationOptions {
            fit,
            ..Default::default()
        };
        let out = calibrate(&start, &data, &options).unwrap();
        assert!(out.converged(), "{name}: {}", out.termination);
        let se = out
            .standard_errors
            .expect("standard errors with more data than unknowns");
        let error = out.fitted.friction - truth.friction;
        eprintln!(
            "{name}: mu = {:.6} +- {:.2e} (truth 0.1, error {error:.2e}); E = {:.4e}; noise estimate {:.3e} m; {} iterations",
            out.fitted.friction, se.friction, out.fitted.youngs_modulus, out.noise_estimate, out.iterations
        );
        // Four standard errors: a Gaussian estimate falls outside with probability 6e-5.
        assert!(
            error.abs() <= 4.0 * se.friction,
            "{name}: mu error {error:.3e}, se {:.3e}",
            se.friction
        );
        // The noise is resolved: the standard error is far below mu itself.
        assert!(se.friction < 0.01 * truth.friction, "{name}: se {:.3e}", se.friction);
        if !only_mu {
            let e = out.fitted.youngs_modulus - truth.youngs_modulus;
            assert!(
                e.abs() <= 4.0 * se.youngs_modulus,
                "{name}: E error {e:.3e}, se {:.3e}",
                se.youngs_modulus
            );
        }
        // The fitted robot carries the fitted mu.
        let fitted = out.robot.tendons[0].friction.unwrap();
        assert_eq!(fitted.coefficient, out.fitted.friction);
    }
}

#[test]
fn the_experiments_csv_carries_the_motion() {
    let mut data = experiments();
    data[0].motion = None;
    let text = to_csv(&data);
    assert!(text.lines().next().unwrap().ends_with(",motion"), "{text}");
    let back = parse_csv(&text, "data.csv", 5).unwrap();
    assert_eq!(back, data);
    // Without motions the file has no motion column, as before friction.
    for e in &mut data {
        e.motion = None;
    }
    assert!(!to_csv(&data).contains("motion"));
    let bad = parse_csv(
        "tension_1,tension_2,tension_3,tension_4,tension_5,tip_force_x,tip_force_y,tip_force_z,measured_x,measured_y,measured_z,motion\n\
         1,0,0,0,0,0,0,0,0,0,0.2,unload\n",
        "data.csv",
        5,
    )
    .unwrap_err();
    let message = bad.to_string();
    assert!(message.contains("`motion`") && message.contains("release"), "{message}");
    // The names and what they mean are those the command line's --motion gives.
    assert!(message.contains("give `pull` (the actuator pulls the tendon in: a loading step) or `release` (it lets it out: an unloading step) or leave it empty"), "{message}");
}

#[test]
fn fitting_mu_needs_friction_and_a_positive_start() {
    let data = experiments();
    let options = CalibrationOptions {
        fit: Fit {
            friction: true,
            ..Fit::none()
        },
        ..Default::default()
    };
    match calibrate(&prototype_in_paper_frame(), &data, &options) {
        Err(Error::InvalidInput { field, hint, .. }) => {
            assert_eq!(field, "robot.tendons");
            assert!(hint.contains("friction = 0.1"), "{hint}");
        }
        other => panic!("expected an error, got {other:?}"),
    }
    let mut start = Parameters::of(&robot(0.1));
    start.friction = 0.0;
    let options = CalibrationOptions {
        start: Some(start),
        ..options
    };
    match calibrate(&robot(0.1), &data, &options) {
        Err(Error::InvalidInput { field, .. }) => assert_eq!(field, "options.start.friction"),
        other => panic!("expected an error, got {other:?}"),
    }
}

#[test]
fn the_command_fits_mu() {
    // `tdcr example paper-robot` with friction 0.05 on tendon 1 as the start; the data made
    // with mu = 0.1 (no noise).
    let mut text = tdcr::io::paper_frame_example();
    let first = text.find("tension = 0.0\n").unwrap() + "tension = 0.0\n".len();
    text.insert_str(first, "friction = 0.05\n");
    let start = tdcr::io::parse(&text, "robot.toml").unwrap().robot;
    let mut truth = Parameters::of(&start);
    truth.friction = 0.1;
    let mut data = experiments();
    let tips = predict(&start, &truth, &data, &CalibrationOptions::default()).unwrap();
    for (e, tip) in data.iter_mut().zip(tips) {
        e.measured_tip = tip;
    }
    let dir = std::env::temp_dir().join(format!("tdcr-friction-calibration-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("robot.toml"), &text).unwrap();
    std::fs::write(dir.join("experiments.csv"), to_csv(&data)).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_tdcr"))
        .args(["calibrate", "robot.toml", "experiments.csv", "--fit", "mu"])
        .current_dir(&dir)
        .output()
        .unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let row = stdout
        .lines()
        .find(|l| l.starts_with("mu "))
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(row.contains("0.0500") && row.contains("0.1000"), "{row}");
    assert!(stdout.contains("friction = 0.100000"), "{stdout}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Tendons whose coefficients differ keep their ratios: the fit scales them together (mu
/// is the first one's), and a fit without mu leaves each its own (before, every forward
/// solve of the fit gave all of them the first one's).
#[test]
fn different_coefficients_keep_their_ratios() {
    // Tendons 1 and 2 (at right angles) with mu 0.05 and 0.15; the truth twice both.
    let mut start = robot(0.05);
    start.tendons[1].friction = Some(Friction::pull(0.15));
    let mut data = experiments();
    for e in &mut data {
        e.tensions[1] = 0.5 * e.tensions[0];
    }
    let mut truth = Parameters::of(&start);
    assert_eq!(truth.friction, 0.05);
    truth.friction = 0.1;
    let applied = truth.apply(&start);
    // 1e-15 relative: the ratio 3 times 2, rounded once.
    let second = applied.tendons[1].friction.unwrap().coefficient;
    assert!((second / 0.3 - 1.0).abs() < 1e-15, "{second}");
    let tips = predict(&start, &truth, &data, &CalibrationOptions::default()).unwrap();
    for (e, tip) in data.iter_mut().zip(tips) {
        e.measured_tip = tip;
    }
    let options = CalibrationOptions {
        fit: Fit {
            friction: true,
            ..Fit::none()
        },
        ..CalibrationOptions::default()
    };
    let fit = calibrate(&start, &data, &options).unwrap();
    assert!(fit.converged(), "{}", fit.termination);
    // 1e-8: noise-free data made by the same model on the same mesh; a wrong column (the
    // plain sum) would still converge, but more slowly: the value is what is checked.
    assert!(
        (fit.fitted.friction / 0.1 - 1.0).abs() < 1e-8,
        "{}",
        fit.fitted.friction
    );
    let fitted = fit.robot.tendons[1].friction.unwrap().coefficient;
    assert!((fitted / 0.3 - 1.0).abs() < 1e-8, "{fitted}");
    // The fit's column d(tips)/d(mu) weighs tendon 2's by its ratio 3: mu's standard error
    // is the noise estimate over the column's norm (one unknown), which a central
    // difference of the predicted tips gives too. 1e-4: the difference's truncation and the
    // noise estimate's rounding (the plain sum of the columns is off by far more).
    let h = 1e-6 * fit.fitted.friction;
    let tips = |mu: f64| {
        let p = Parameters {
            friction: mu,
            ..fit.fitted
        };
        predict(&start, &p, &data, &CalibrationOptions::default()).unwrap()
    };
    let (up, down) = (tips(fit.fitted.friction + h), tips(fit.fitted.friction - h));
    let norm = up
        .iter()
        .zip(&down)
        .map(|(a, b)| ((a - b) / (2.0 * h)).norm_squared())
        .sum::<f64>()
        .sqrt();
    let error = fit.standard_errors.expect("standard errors").friction;
    assert!(
        (error * norm / fit.noise_estimate - 1.0).abs() < 1e-4,
        "{error} {norm} {}",
        fit.noise_estimate
    );
    // E alone: the coefficients are the robot's own in every solve and in the result.
    let e_only = CalibrationOptions {
        fit: Fit {
            youngs_modulus: true,
            ..Fit::none()
        },
        ..CalibrationOptions::default()
    };
    let fit = calibrate(&start, &data, &e_only).unwrap();
    assert_eq!(fit.robot.tendons[0].friction.unwrap().coefficient, 0.05);
    assert_eq!(fit.robot.tendons[1].friction.unwrap().coefficient, 0.15);
}
