//! The picture of `tdcr sweep`: the tip trajectory, the first and last shapes, the shapes of
//! `--shapes` in between, and every snap (a jump of the tip between two steps) marked: the
//! shapes on either side of it and a dashed chord where the tip jumped.

use tdcr::plot::{Curve, Figure, LegendEntry, Marker, Style, Symbol, shape_legend};
use tdcr::{Robot, Solution};

/// A solved step's robot and solution, as the picture draws it.
pub type Shape = (Robot, Solution);

/// Colour of the tip trajectory (Okabe-Ito blue).
const TRAJECTORY: &str = "#0072B2";
/// Colour of snaps: the shapes around one and the tip's jump (Okabe-Ito vermillion).
const SNAP: &str = "#D55E00";

/// The steps whose shapes are drawn: `count` evenly spaced over `steps` steps, the first and
/// last among them (`None`: every step).
pub fn chosen(count: Option<usize>, steps: usize) -> Vec<usize> {
    match count {
        None => (0..steps).collect(),
        Some(_) if steps == 0 => Vec::new(),
        Some(n) if n <= 1 || steps == 1 => vec![steps - 1],
        Some(n) => {
            let mut k: Vec<usize> = (0..n.min(steps))
                .map(|j| (j as f64 * (steps - 1) as f64 / (n.min(steps) - 1) as f64).round() as usize)
                .collect();
            k.dedup();
            k
        }
    }
}

/// What the sweep hands the picture: the tips of every step, the chosen steps' shapes (in
/// step order) and each snap's step (the step after the jump) with the shapes either side.
#[derive(Default)]
pub struct Drawn {
    /// The tip of every solved step (m).
    pub tips: Vec<tdcr::nalgebra::Vector3<f64>>,
    /// (step, shape) for the chosen steps.
    pub shapes: Vec<(usize, Shape)>,
    /// (step after the jump, the shape before it, the shape after it, what happened).
    pub snaps: Vec<(usize, Shape, Shape, String)>,
}

/// The picture: `title`, the swept `ranges` as the subtitle, `disks` on the first and last
/// shapes (`None`: the default count).
pub fn picture(title: &str, ranges: String, disks: Option<usize>, drawn: &Drawn) -> Figure {
    let mut figure = Figure::new(title);
    figure.subtitle.push(ranges);
    let last_index = drawn.shapes.len().saturating_sub(1);
    let mut end = Style::new("#444444");
    for (j, (_, (robot, solution))) in drawn.shapes.iter().enumerate() {
        let style = if j == last_index {
            end.disks = disks;
            end.clone()
        } else if j == 0 {
            let mut s = Style::new("#888888");
            s.dash = Some("5 3".into());
            s.disks = disks;
            s.distributed_load = false;
            s
        } else {
            let mut s = Style::new("#9a9a9a");
            s.opacity = 0.55;
            s.disks = Some(0);
            s.loads = false;
            s.distributed_load = false;
            s
        };
        figure.add_shape(robot, solution, &style);
    }
    for (_, (r0, s0), (r1, s1), _) in &drawn.snaps {
        let mut s = Style::new(SNAP);
        s.disks = Some(0);
        s.loads = false;
        s.distributed_load = false;
        s.opacity = 0.8;
        figure.add_shape(r0, s0, &s);
        s.dash = Some("2 2".into());
        figure.add_shape(r1, s1, &s);
    }
    // The trajectory, solid between snaps, a dashed chord across each.
    let mut from = 0;
    let mut cuts: Vec<usize> = drawn.snaps.iter().map(|(k, ..)| *k).collect();
    cuts.push(drawn.tips.len());
    let panel = figure.panel_mut();
    for &k in &cuts {
        if k > from {
            panel.curves.push(Curve {
                points: drawn.tips[from..k].to_vec(),
                color: TRAJECTORY.into(),
                width: 2.0,
                dash: None,
                opacity: 1.0,
            });
        }
        if k < drawn.tips.len() && k > 0 {
            panel.curves.push(Curve {
                points: vec![drawn.tips[k - 1], drawn.tips[k]],
                color: SNAP.into(),
                width: 2.0,
                dash: Some("6 4".into()),
                opacity: 1.0,
            });
        }
        from = k;
    }
    panel.markers.extend(drawn.tips.iter().map(|&point| Marker {
        point,
        color: TRAJECTORY.into(),
        radius: 1.8,
    }));
    let between = drawn.shapes.len().saturating_sub(2);
    figure.legend = vec![
        LegendEntry::line("tip trajectory (a dot per solve)", TRAJECTORY).width(2.0),
        LegendEntry::line("first shape", "#888888").dash("5 3"),
        LegendEntry::line("last shape", "#444444"),
    ];
    if between > 0 {
        figure.legend.push(
            LegendEntry::line(
                &format!(
                    "{between} shape{} in between (light)",
                    if between == 1 { "" } else { "s" }
                ),
                "#9a9a9a",
            )
            .width(1.5),
        );
    }
    figure
        .legend
        .push(LegendEntry::line("pulled tendons of each shape (thin lines)", "#444444").width(1.2));
    for (k, _, _, what) in &drawn.snaps {
        figure.legend.push(
            LegendEntry::line(
                &format!("step {}: {what}; shapes before (solid) and after (dotted)", k + 1),
                SNAP,
            )
            .dash("6 4"),
        );
    }
    // Disks and loads of the last shape.
    if let Some((_, (robot, _))) = drawn.shapes.last() {
        let legend = shape_legend(robot, &end);
        figure
            .legend
            .extend(legend.into_iter().filter(|e| e.symbol != Symbol::Line));
    }
    figure
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chosen_steps_are_evenly_spaced_with_both_ends() {
        assert_eq!(chosen(Some(2), 13), vec![0, 12]);
        assert_eq!(chosen(Some(5), 13), vec![0, 3, 6, 9, 12]);
        assert_eq!(chosen(Some(20), 3), vec![0, 1, 2]);
        assert_eq!(chosen(None, 3), vec![0, 1, 2]);
        assert_eq!(chosen(Some(1), 4), vec![3]);
    }
}
