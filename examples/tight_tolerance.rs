//! Tight tolerances: for cases S and H at tolerances from 1e-7 L to 1e-12 L, the mesh the
//! error control ends on, the estimated and the true tip errors (against collocation on
//! 4096 intervals, order 4: about 1e-15 m on these cases) and their ratio
//! (docs/benchmarks.md, "Tight tolerances").
//!
//! `cargo run --release --example tight_tolerance`

use tdcr::{cases, collocation, so3};

fn main() -> Result<(), tdcr::Error> {
    println!(
        "| case | tol (L) | intervals | meshes | tip error (m) | estimate (m) | true / estimate | rotation error (rad) | estimate (rad) |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for (name, robot) in [("S", cases::case_s()), ("H", cases::case_h())] {
        let fine = |intervals| collocation::Options {
            residual_tolerance: 1e-14,
            ..collocation::Options::fixed(intervals)
        };
        let reference = collocation::solve(&robot, &fine(4096))?;
        let (p_ref, r_ref) = (reference.tip_position(), reference.tip().R);
        let check = collocation::solve(&robot, &fine(2048))?;
        eprintln!(
            "{name}: reference on 2048 vs 4096 intervals: {:.2e} m, {:.2e} rad",
            (check.tip_position() - p_ref).norm(),
            so3::log(&(r_ref.transpose() * check.tip().R)).norm()
        );
        for tol in [1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12] {
            let options = collocation::Options {
                tolerance: Some(tol),
                ..Default::default()
            };
            let s = collocation::solve(&robot, &options)?;
            let e = s.report.error_estimate.expect("an estimate");
            let dp = (s.tip_position() - p_ref).norm();
            let dr = so3::log(&(r_ref.transpose() * s.tip().R)).norm();
            println!(
                "| {name} | {tol:.0e} | {} | {} | {dp:.2e} | {:.2e} | {:.3} | {dr:.2e} | {:.2e} |",
                s.report.intervals,
                s.report.meshes,
                e.tip_position,
                dp / e.tip_position,
                e.tip_rotation
            );
        }
    }
    Ok(())
}
