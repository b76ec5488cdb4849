//! Calibration walk-through (docs/calibration.md): make synthetic measurements of the
//! paper's prototype under all 32 experiments of Table 2 with the paper's calibrated
//! parameters (E = 230 GPa, XYZ Euler angles (177.8, 2.2, -89.7) deg) plus Gaussian noise,
//! write them as a robot file and an experiments CSV for `tdcr calibrate`, then fit E and the
//! angles from the nominal start (210 GPa, (180, 0, -90) deg) with the library.
//!
//! `cargo run --release --example calibration -- [DIR] [NOISE_MM]`
//! (default `out/calibration` and 0.1 mm per coordinate).

use tdcr::cases::{self, prototype_in_paper_frame};
use tdcr::fit::calibration::{CalibrationOptions, Parameters, TipErrorStatistics, calibrate};
use tdcr::io::experiments::to_csv;
use tdcr::io::{calibration_truth, example_experiments, paper_frame_example};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let dir = std::path::PathBuf::from(args.get(1).map_or("out/calibration", String::as_str));
    let noise_mm: f64 = args.get(2).map_or(Ok(0.1), |s| s.parse())?;
    let noise = noise_mm * 1e-3;

    // 1. The robot at its nominal parameters, and the truth that made the "measurements".
    let robot = prototype_in_paper_frame();
    let nominal = Parameters::of(&robot);
    let truth = calibration_truth();

    // 2. Synthetic experiments: Table 2's loads, tips from the truth plus noise (the same
    // files as `tdcr example paper-robot` and `tdcr example experiments` at 0.1 mm).
    let table = cases::table2();
    let experiments = example_experiments(noise)?;
    let options = CalibrationOptions::default();
    std::fs::create_dir_all(&dir)?;
    std::fs::write(dir.join("robot.toml"), paper_frame_example())?;
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
