//! Calibration walk-through (docs/calibration.md): make synthetic measurements of the
//! paper's prototype under all 32 experiments of Table 2 with the paper's calibrated
//! parameters (E = 230 GPa, XYZ Euler angles (177.8, 2.2, -89.7) deg) plus Gaussian noise,
//! write them as a robot file and an experiments CSV for `tdcr calibrate`, then fit E and the
//! angles from the nominal start (210 GPa, (180, 0, -90) deg) with the library.
//!
//! `cargo run --release --example calibration -- [DIR] [NOISE_MM]`
//! (default `out/calibration` and 0.1 mm per coordinate).

use nalgebra::Vector3;
use std::fmt::Write as _;
use tdcr::cases::{GaussianNoise, paper_frame_rotation, prototype_in_paper_frame, table2_measurement};
use tdcr::fit::calibration::{CalibrationOptions, Measurement, Parameters, TipErrorStatistics, calibrate, predict};
use tdcr::io::experiments::to_csv;
use tdcr::{Routing, cases};

/// The prototype in the paper's frame as a robot file: nominal E and base angles, gravity
/// along +y, the five tendons of Table 1 (tensions come from the CSV).
fn robot_file() -> String {
    let g = paper_frame_rotation() * Vector3::new(0.0, 0.0, -cases::WEIGHT_PER_LENGTH);
    let [a, b, c] = cases::PAPER_NOMINAL_EULER_DEG;
    let mut text = format!(
        "# The prototype of Rucker & Webster (2011) in the paper's frame: the base at the nominal\n\
         # XYZ Euler angles of section 5.1, gravity along +y. Made by examples/calibration.rs.\n\n\
         [rod]\nlength = {}\nouter_radius = {}\nyoungs_modulus = {:e}\npoisson_ratio = {}\n\n\
         [base]\nposition = [0.0, 0.0, 0.0]\neuler_xyz_deg = [{a:?}, {b:?}, {c:?}]\n\n\
         [loads]\ndistributed_force = [{:?}, {:?}, {:?}]   # N/m, self weight\n",
        cases::LENGTH,
        cases::RADIUS,
        cases::YOUNGS_MODULUS,
        cases::POISSON_RATIO,
        g.x + 0.0,
        g.y + 0.0,
        g.z + 0.0
    );
    for (i, routing) in cases::prototype_routings().iter().enumerate() {
        let routing = match routing {
            Routing::Straight { x, y } => format!("{{ kind = \"straight\", x = {x:?}, y = {y:?} }}"),
            Routing::Helical { radius, turns, phase } => {
                format!("{{ kind = \"helical\", radius = {radius:?}, turns = {turns:?}, phase = {phase:?} }}")
            }
            Routing::Custom(_) => unreachable!("the prototype's routings are straight or helical"),
        };
        let _ = write!(
            text,
            "\n[[tendon]]   # tendon {}\nrouting = {routing}\ntension = 0.0\n",
            i + 1
        );
    }
    text.push_str("\n[solver]\nnodes = 32\n");
    text
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let dir = std::path::PathBuf::from(args.get(1).map_or("out/calibration", String::as_str));
    let noise_mm: f64 = args.get(2).map_or(Ok(0.1), |s| s.parse())?;
    let noise = noise_mm * 1e-3;

    // 1. The robot at its nominal parameters, and the truth that made the "measurements".
    let robot = prototype_in_paper_frame();
    let nominal = Parameters::of(&robot);
    let truth = Parameters {
        youngs_modulus: cases::PAPER_CALIBRATED_YOUNGS_MODULUS,
        euler: Vector3::from(cases::PAPER_CALIBRATED_EULER_DEG).map(f64::to_radians),
        ..nominal
    };

    // 2. Synthetic experiments: Table 2's loads, tips from the truth plus noise.
    let table = cases::table2();
    let mut experiments: Vec<Measurement> = table
        .iter()
        .map(|e| table2_measurement(e, &paper_frame_rotation()))
        .collect();
    let options = CalibrationOptions::default();
    let tips = predict(&robot, &truth, &experiments, &options)?;
    let mut gauss = GaussianNoise::new(2011);
    for (e, tip) in experiments.iter_mut().zip(tips) {
        e.measured_tip = tip + noise * Vector3::new(gauss.next(), gauss.next(), gauss.next());
    }
    std::fs::create_dir_all(&dir)?;
    std::fs::write(dir.join("robot.toml"), robot_file())?;
    std::fs::write(dir.join("experiments.csv"), to_csv(&experiments))?;
    println!(
        "wrote {0}/robot.toml and {0}/experiments.csv: {1} experiments, noise {noise_mm} mm per coordinate\n\
         try: cargo run --release -- calibrate {0}/robot.toml {0}/experiments.csv\n",
        dir.display(),
        experiments.len()
    );

    // 3. Fit E and the Euler angles from the nominal start.
    let fit = calibrate(&robot, &experiments, &options)?;
    println!(
        "{} after {} iterations ({} solves, {:.2} s)",
        fit.termination,
        fit.iterations,
        fit.solves,
        fit.timings.total.as_secs_f64()
    );
    let se = fit.standard_errors.unwrap_or(fit.fitted);
    println!("parameter   nominal    fitted     std. error   truth");
    println!(
        "E (GPa)     {:>7.2}   {:>9.4}   {:>8.4}   {:>7.2}",
        nominal.youngs_modulus / 1e9,
        fit.fitted.youngs_modulus / 1e9,
        se.youngs_modulus / 1e9,
        truth.youngs_modulus / 1e9
    );
    for (i, name) in ["alpha", "beta", "gamma"].iter().enumerate() {
        println!(
            "{:<11} {:>7.2}   {:>9.4}   {:>8.4}   {:>7.2}",
            format!("{name} (deg)"),
            nominal.euler_deg()[i],
            fit.fitted.euler_deg()[i],
            se.euler_deg()[i],
            truth.euler_deg()[i]
        );
    }

    // 4. Table 3: tip errors before and after, straight and helical tendons apart.
    let helical = |k: usize| table[k].tendon == Some(5);
    let split = |errors: &[f64], want: bool| -> Vec<f64> {
        (0..errors.len())
            .filter(|&k| table[k].tendon.is_some() && helical(k) == want)
            .map(|k| errors[k])
            .collect()
    };
    let (before, after) = (fit.start_tip_errors(), fit.tip_errors());
    println!("\ntip error (mm), before / after   straight          helical           all");
    let groups = [
        (
            TipErrorStatistics::of(&split(&before, false)),
            TipErrorStatistics::of(&split(&after, false)),
        ),
        (
            TipErrorStatistics::of(&split(&before, true)),
            TipErrorStatistics::of(&split(&after, true)),
        ),
        (fit.start_errors, fit.errors),
    ];
    let rows: [(&str, Statistic); 4] = [
        ("mean", |t| t.mean),
        ("min", |t| t.min),
        ("max", |t| t.max),
        ("std. dev.", |t| t.std_dev),
    ];
    for (label, get) in rows {
        let cells: Vec<String> = groups
            .iter()
            .map(|(b, a)| format!("{:>6.2} / {:<6.3}", get(b) * 1e3, get(a) * 1e3))
            .collect();
        println!("{label:<32} {}", cells.join("   "));
    }
    Ok(())
}

/// One statistic of a [`TipErrorStatistics`] (m).
type Statistic = fn(&TipErrorStatistics) -> f64;
