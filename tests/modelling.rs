//! The worked robots of docs/modelling.md: each robot file on the page reads, solves, and
//! puts its tip where the page says.

use tdcr::collocation;

const PAGE: &str = include_str!("../docs/modelling.md");

/// The page's ```toml blocks that are robot files (start with `[rod]` or `[[segment]]`).
fn robots() -> Vec<String> {
    PAGE.split("```toml\n")
        .skip(1)
        .filter_map(|block| block.split("```").next())
        .filter(|text| text.starts_with("[rod]") || text.starts_with("[[segment]]"))
        .map(str::to_string)
        .collect()
}

/// The tips the page gives, in mm: the numbers of each `Solved tip: (x, y, z) mm` line.
fn tips() -> Vec<[f64; 3]> {
    PAGE.split("Solved tip: (")
        .skip(1)
        .map(|rest| {
            let numbers: Vec<f64> = rest
                .split(')')
                .next()
                .unwrap()
                .split(',')
                .map(|x| x.trim().parse().unwrap())
                .collect();
            [numbers[0], numbers[1], numbers[2]]
        })
        .collect()
}

#[test]
fn worked_robots_solve_to_the_tips_on_the_page() {
    let (robots, tips) = (robots(), tips());
    assert_eq!((robots.len(), tips.len()), (3, 3));
    for (k, (text, tip)) in robots.iter().zip(&tips).enumerate() {
        let file = tdcr::io::parse(text, &format!("robot {}", k + 1)).unwrap();
        assert!(file.robot.plausibility().is_empty(), "robot {}", k + 1);
        let solved = collocation::solve(&file.robot, &file.solver.collocation).unwrap();
        let p = solved.tip_position() * 1e3;
        for i in 0..3 {
            // 0.005 mm: the page prints two decimals (the solve is within 1e-7 L of exact)
            assert!((p[i] - tip[i]).abs() <= 0.005 + 1e-9, "robot {}: {p} vs {tip:?}", k + 1);
        }
    }
}

#[test]
fn the_disks_of_robot_one_move_its_tip_by_15_mm() {
    let text = &robots()[0];
    let (start, end) = (text.find("[disks]").unwrap(), text.find("[[tendon]]").unwrap());
    let without = format!("{}{}", &text[..start], &text[end..]);
    let tip = |t: &str| {
        let file = tdcr::io::parse(t, "robot").unwrap();
        collocation::solve(&file.robot, &file.solver.collocation)
            .unwrap()
            .tip_position()
    };
    let moved = (tip(text) - tip(&without)).norm();
    // The page says 15 mm (measured 15.2 mm): 0.5 mm either side of that
    assert!((moved - 0.015).abs() < 5e-4, "{moved}");
}
