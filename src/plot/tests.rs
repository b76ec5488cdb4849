//! What the pictures must show: ticks, legend entries naming the tendons, disks, arrows,
//! wrapped subtitles, small multiples, true helix turns, and PNG files of the asked size.

use super::*;
use crate::cases;
use crate::model::routing::{Routing, RoutingPoint};
use crate::model::tendon::Tendon;
use axes::significant;

fn solve(robot: &Robot) -> Solution {
    crate::collocation::solve(robot, &Default::default()).unwrap()
}

fn count(svg: &str, needle: &str) -> usize {
    svg.matches(needle).count()
}

/// Case S drawn with every tendon, 12 disks, and its legend.
fn case_s_figure() -> Figure {
    let robot = cases::case_s();
    let mut style = Style::new("#000000");
    style.slack_tendons = true;
    style.tendon_colors = true;
    style.disks = Some(12);
    let mut figure = Figure::new("case S");
    figure.add_shape(&robot, &solve(&robot), &style);
    figure.legend = shape_legend(&robot, &style);
    figure
}

#[test]
fn orthographic_views_have_tick_numbers_and_axis_labels_in_mm() {
    let svg = case_s_figure().to_svg();
    // Three orthographic views, each with at least 3 numbers on each of its two axes.
    assert!(count(&svg, r#"class="tick""#) >= 3 * 6, "{svg}");
    for label in ["x (mm)", "y (mm)", "z (mm)"] {
        assert!(svg.contains(label), "{label}");
    }
    // The base is at the origin: 0 is a tick of every axis.
    assert!(svg.contains(">0</text>"));
}

#[test]
fn legend_names_the_thin_lines_as_tendons_with_their_tension() {
    let figure = case_s_figure();
    let svg = figure.to_svg();
    assert!(
        svg.contains("tendon 1 (thin line): straight at (8, 0) mm; 2.94 N"),
        "{svg}"
    );
    assert!(svg.contains("backbone (thick line)"));
    let slack = &figure.legend[2];
    assert_eq!(
        slack.label,
        "tendon 2 (thin dashed line): straight at (0, 8) mm; slack (0 N)"
    );
    assert_eq!(slack.dash.as_deref(), Some(shape::SLACK_DASH));
}

#[test]
fn slack_tendons_are_drawn_dashed_and_visible() {
    let svg = case_s_figure().to_svg();
    // Four slack tendons in four views, dashed, at opacity 0.8.
    let slack = format!(
        r#"stroke-opacity="0.8" stroke-linejoin="round" stroke-linecap="round" stroke-dasharray="{}""#,
        shape::SLACK_DASH
    );
    assert_eq!(count(&svg, &slack), 4 * 4, "{svg}");
}

#[test]
fn disks_are_drawn_as_many_as_asked_in_every_view() {
    let figure = case_s_figure();
    assert_eq!(figure.panels[0].disks.len(), 12);
    assert_eq!(count(&figure.to_svg(), r#"class="disk""#), 12 * 4);
    assert!(figure.legend.iter().any(|e| e.label.starts_with("12 spacer disks")));
    // The default for the prototype's 8 mm tendons on 242 mm is its 12 disks too.
    assert_eq!(default_disks(&cases::case_s()), 12);
}

#[test]
fn tip_force_gets_an_arrow_labelled_in_newtons() {
    let robot = cases::case_h();
    let style = Style::new("#000000");
    let mut figure = Figure::new("case H");
    figure.add_shape(&robot, &solve(&robot), &style);
    figure.legend = shape_legend(&robot, &style);
    let svg = figure.to_svg();
    // One tip-force arrow per view (the -z force is seen end-on from the top: a symbol).
    assert_eq!(count(&svg, r#"class="arrow""#), 4, "{svg}");
    assert!(svg.contains(">0.196 N</text>"));
    assert!(svg.contains("tip force 0.196 N"));
    // Self weight: six small arrows per view, labelled once in N/m.
    assert!(count(&svg, r#"class="load-hint""#) >= 6 * 3);
    assert!(svg.contains(">0.47 N/m</text>"));

    let unloaded = cases::case_s();
    let mut figure = Figure::new("case S");
    figure.add_shape(&unloaded, &solve(&unloaded), &style);
    assert_eq!(count(&figure.to_svg(), r#"class="arrow""#), 0);
}

#[test]
fn long_subtitles_wrap_instead_of_leaving_the_picture() {
    let mut figure = case_s_figure();
    let long = "collocation (error-controlled): 32 -> 64 -> 128 -> 256 intervals, estimated tip error \
                3.1e-9 m <= 2.42e-8 m (met), 9 Newton iterations, 2 Jacobian evaluations, 3 chord steps, \
                1 load step, residual 4.4e-13, 5.9 ms";
    figure.subtitle.push(long.into());
    let svg = figure.to_svg();
    let lines: Vec<&str> = svg.lines().filter(|l| l.contains(r#"class="subtitle""#)).collect();
    assert!(lines.len() >= 2, "{lines:?}");
    let width: f64 = svg.split('"').nth(3).unwrap().parse().unwrap();
    for line in lines {
        let text = line.split('>').nth(1).unwrap().trim_end_matches("</text");
        let text = text.replace("&gt;", ">").replace("&lt;", "<").replace("&amp;", "&");
        // 0.6 em per glyph over-estimates DejaVu Sans, the widest face named; 24 px margins.
        assert!(text.chars().count() as f64 * 12.0 * 0.6 <= width - 48.0, "{text}");
    }
}

#[test]
fn several_panels_make_small_multiples_with_ticks_in_every_cell() {
    let mut figure = Figure::new("two panels");
    for (title, robot) in [("S", cases::case_s()), ("H", cases::case_h())] {
        figure.add_panel(title);
        figure.add_shape(&robot, &solve(&robot), &Style::new("#000000"));
    }
    let svg = figure.to_svg();
    assert_eq!(count(&svg, "side view (XZ)"), 2);
    assert_eq!(count(&svg, ">perspective<"), 2);
    // Horizontal numbers under each of the 6 orthographic cells.
    assert_eq!(count(&svg, "x (mm)</text>"), 2 * 2);
    assert_eq!(count(&svg, "y (mm)</text>"), 2 + 1);
}

/// A helix of one turn per rod length written as a custom routing: independent of what the
/// `turns` of [`Routing::Helical`] counts.
fn one_turn_per_length(radius: f64) -> Routing {
    Routing::custom(move |s, length| {
        let k = std::f64::consts::TAU / length;
        let (c, d) = ((k * s).cos(), (k * s).sin());
        RoutingPoint {
            r: nalgebra::Vector3::new(radius * c, radius * d, 0.0),
            r_s: nalgebra::Vector3::new(-radius * k * d, radius * k * c, 0.0),
            r_ss: nalgebra::Vector3::new(-radius * k * k * c, -radius * k * k * d, 0.0),
        }
    })
}

#[test]
fn turns_count_over_the_tendons_own_length() {
    let length = cases::LENGTH;
    let half = Tendon::new(one_turn_per_length(0.008), 1.0).ending_at(length / 2.0);
    // 1e-9 turns: the unwrapped angle is exact to rounding
    assert!((half.turns(length) - 0.5).abs() < 1e-9);
    let full = Tendon::new(one_turn_per_length(0.008), 1.0);
    assert!((full.turns(length) - 1.0).abs() < 1e-9);
    let left = Tendon::new(Routing::helical(0.008, -3.0, 0.4), 1.0);
    assert!((left.turns(length) + 3.0).abs() < 1e-9);
    assert_eq!(Tendon::new(Routing::straight(0.008, 0.0), 1.0).turns(length), 0.0);
    assert_eq!(turns_label(0.5), "0.5 turns");
    assert_eq!(turns_label(1.0), "1 turn");
    assert_eq!(turns_label(-3.0), "-3 turns (left-handed)");
}

#[test]
fn legend_shows_half_a_turn_for_a_helix_ending_at_half_length() {
    let mut robot = cases::prototype();
    // The prototype's tendon 5 is a helix of one turn over the rod length.
    robot.tendons[4] = Tendon::new(robot.tendons[4].routing.clone(), 2.0).ending_at(cases::LENGTH / 2.0);
    assert_eq!(
        tendon_label(&robot, 4),
        "tendon 5: helix of radius 8 mm, 0.5 turns, ends at s = 121 mm; 2 N"
    );
    robot.tendons[3] = Tendon::new(one_turn_per_length(0.008), 0.0).ending_at(cases::LENGTH / 2.0);
    assert_eq!(
        tendon_label(&robot, 3),
        "tendon 4: custom routing, 0.5 turns, ends at s = 121 mm; slack (0 N)"
    );
}

#[test]
fn tendon_paths_come_from_the_dense_interpolant() {
    let mut robot = cases::prototype();
    robot.tendons[4] = Tendon::new(Routing::helical(0.008, 3.0, 0.0), 1.0);
    let solution = solve(&robot);
    let path = tendon_path(&robot, &solution, 4);
    // At least 64 points per turn, many more than the mesh has nodes.
    assert!(
        path.len() > 3 * 64 && path.len() > solution.nodes.len(),
        "{}",
        path.len()
    );
    let nodes = &solution.tendon_paths[4];
    for (a, b) in [(path[0], nodes[0]), (path[path.len() - 1], nodes[nodes.len() - 1])] {
        // 1e-12 m: the interpolant reproduces the nodes up to rounding
        assert!((a - b).norm() < 1e-12, "{a} vs {b}");
    }
}

#[test]
fn file_formats_follow_the_extension() {
    assert_eq!(Format::from_path(Path::new("a/shape.PNG")).unwrap(), Format::Png);
    assert_eq!(Format::from_path(Path::new("shape.svg")).unwrap(), Format::Svg);
    assert_eq!(Format::from_path(Path::new("shape")).unwrap(), Format::Svg);
    let e = Format::from_path(Path::new("shape.jpg")).unwrap_err().to_string();
    assert!(e.contains(".jpg") && e.contains("FILE.png"), "{e}");
}

/// Width and height from a PNG's IHDR chunk.
fn png_size(data: &[u8]) -> (u32, u32) {
    let word = |k: usize| u32::from_be_bytes([data[k], data[k + 1], data[k + 2], data[k + 3]]);
    (word(16), word(20))
}

#[test]
fn png_has_the_signature_and_the_asked_size() {
    let figure = case_s_figure();
    let svg = figure.to_svg();
    let number = |k: usize| -> f64 { svg.split('"').nth(k).unwrap().parse().unwrap() };
    let (width, height) = (number(3), number(5));
    for scale in [1.0, 2.0] {
        let png = figure.to_png(scale).unwrap();
        assert_eq!(&png.data[..8], b"\x89PNG\r\n\x1a\n");
        let asked = ((width * scale).round() as u32, (height * scale).round() as u32);
        assert_eq!(png_size(&png.data), asked);
        assert_eq!((png.width, png.height), asked);
    }
    assert!(figure.to_png(0.0).is_err());
}

#[test]
fn png_text_is_set_when_the_system_has_fonts() {
    let with = Figure::new("WWWWWWWWWWWWWWWWWWWW").to_png(1.0).unwrap();
    let without = Figure::new("").to_png(1.0).unwrap();
    assert_eq!(with.text, fonts_found());
    // The title is drawn exactly when a font was found to draw it in.
    assert_eq!(with.data != without.data, fonts_found());
}

/// The label boxes ([left, top, right, bottom], px, in the cell's frame) of the arrow labels
/// of each cell of `svg`, estimated as the layout estimates them.
fn label_boxes(svg: &str) -> Vec<Vec<[f64; 4]>> {
    let attr = |tag: &str, name: &str| -> Option<String> {
        let at = tag.find(&format!(" {name}=\""))? + name.len() + 3;
        Some(tag[at..].split('"').next()?.to_string())
    };
    svg.split(r#"<g transform="translate("#)
        .skip(1)
        .map(|cell| {
            cell.split(r#"<g class="arrow">"#)
                .skip(1)
                .filter_map(|group| {
                    let group = group.split("</g>").next()?;
                    let tag = &group[group.find("<text")?..];
                    let (x, y): (f64, f64) = (attr(tag, "x")?.parse().ok()?, attr(tag, "y")?.parse().ok()?);
                    let size: f64 = attr(tag, "font-size")?.parse().ok()?;
                    let text = tag[tag.find('>')? + 1..tag.find("</text>")?].to_string();
                    let w = super::text::text_width(&text, size);
                    let x0 = match attr(tag, "text-anchor")?.as_str() {
                        "start" => x,
                        "end" => x - w,
                        _ => x - w / 2.0,
                    };
                    Some([x0, y - size, x0 + w, y + 2.0])
                })
                .collect()
        })
        .collect()
}

#[test]
fn force_labels_never_overlap_each_other_and_stay_inside_their_cell() {
    // Two tip loads a factor 2 apart on the same shape family: their arrows and labels crowd
    // the same corner of every view, as in the main job's columns.
    let mut figure = Figure::new("two tip loads");
    for fz in [-0.098, -0.196] {
        let mut robot = cases::case_s();
        robot.loads.tip_force = Vector3::new(0.0, 0.0, fz);
        figure.add_shape(&robot, &solve(&robot), &Style::new("#000000"));
    }
    let svg = figure.to_svg();
    let cells = label_boxes(&svg);
    assert_eq!(cells.len(), 4, "four views");
    let size = 430.0;
    for boxes in &cells {
        assert!(boxes.len() >= 2, "{boxes:?}");
        for (i, a) in boxes.iter().enumerate() {
            // 0.5 px: coordinates are written with one decimal
            assert!(
                a[0] >= -0.5 && a[2] <= size + 0.5 && a[1] >= -0.5 && a[3] <= size + 0.5,
                "{a:?}"
            );
            for b in &boxes[..i] {
                let overlap = a[0] < b[2] - 0.5 && a[2] > b[0] + 0.5 && a[1] < b[3] - 0.5 && a[3] > b[1] + 0.5;
                assert!(!overlap, "{a:?} overlaps {b:?}");
            }
        }
    }
}

#[test]
fn views_that_show_a_dot_are_left_out_and_the_rest_fill_one_row() {
    // An upright rod under a small tip force: from the top it is a dot.
    let mut robot = Robot::new(crate::Rod::solid_circle(0.2, 0.001, 200e9, 0.3));
    robot.loads.tip_force = Vector3::new(0.0, 0.0, -0.01);
    let mut figure = Figure::new("upright");
    figure.add_shape(&robot, &solve(&robot), &Style::new("#000000"));
    let svg = figure.to_svg();
    assert!(!svg.contains("top view (XY)"), "{svg}");
    assert!(svg.contains("side view (XZ)") && svg.contains("front view (YZ)") && svg.contains("perspective"));
    // One row of three 430 px cells (and their gutters): wider than tall.
    let width: f64 = svg
        .split("width=\"")
        .nth(1)
        .unwrap()
        .split('"')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(width, 2.0 * 24.0 + 3.0 * (58.0 + 430.0));
    // Asked for: the views given, in order, at the width and text size given.
    figure.views = Some(vec![View::Perspective, View::Top]);
    figure.width = Some(600.0);
    figure.font_size = Some(9.0);
    figure.title.clear();
    let svg = figure.to_svg();
    assert!(svg.find("perspective").unwrap() < svg.find("top view (XY)").unwrap());
    assert!(!svg.contains("side view") && !svg.contains("upright"));
    assert!(
        svg.starts_with(r#"<svg xmlns="http://www.w3.org/2000/svg" width="600""#),
        "{}",
        &svg[..200]
    );
}

/// Issue 27: a tendon placed at 90 degrees, in polar form or by a computed cosine, is
/// labelled at (0, 8) mm, not at (0.0000000000000612, 8) mm.
#[test]
fn legend_prints_zero_offsets_as_zero() {
    let length = 0.242;
    for routing in [
        Routing::polar(0.008, 90.0),
        Routing::straight(0.008 * std::f64::consts::FRAC_PI_2.cos(), 0.008),
    ] {
        let label = shape::routing_label(&Tendon::new(routing, 1.0), length);
        assert_eq!(label, "straight at (0, 8) mm");
    }
    let label = shape::routing_label(&Tendon::new(Routing::polar(0.01, 120.0), 1.0), length);
    assert_eq!(label, "straight at (-5, 8.66) mm");
}

/// Issue 27: a robot's own disks are drawn at their positions and radius; their weights
/// are named once in the disks' legend entry, not as one arrow each.
#[test]
fn placed_disks_are_drawn_where_they_sit_with_their_weight_in_the_legend() {
    let mut robot = cases::case_s();
    let disks = crate::Disks {
        positions: vec![0.05, 0.1, 0.242],
        weight: nalgebra::Vector3::new(0.0, 0.0, -0.02),
        radius: Some(0.012),
    };
    robot.loads.point.push(crate::PointLoad {
        s: 0.2,
        force: nalgebra::Vector3::new(0.0, 0.0, -0.05),
        moment: nalgebra::Vector3::zeros(),
    });
    robot.loads.point.extend(disks.point_loads());
    let mut style = Style::new("#000000");
    style.placed_disks = Some(disks);
    let solution = solve(&robot);
    let mut figure = Figure::new("disks");
    figure.add_shape(&robot, &solution, &style);
    figure.legend = shape_legend(&robot, &style);
    let drawn = &figure.panels[0].disks;
    assert_eq!(drawn.len(), 3);
    assert_eq!(drawn[1].center, solution.at_limit(0.1, true).p);
    assert_eq!(drawn[1].radius, 0.012);
    let labels: Vec<&str> = figure.legend.iter().map(|e| e.label.as_str()).collect();
    assert!(
        labels.contains(&"3 spacer disks, 0.02 N each (drawn 12 mm in radius)"),
        "{labels:?}"
    );
    // The other point load keeps its arrow and entry; the disks' weights get none.
    assert_eq!(
        labels.iter().filter(|l| l.starts_with("point load")).count(),
        1,
        "{labels:?}"
    );
}

/// Case S with friction `mu` on tendon 1 (pulled in), drawn and labelled as `tdcr solve
/// --plot` does, with the solution.
fn case_s_with_friction(mu: f64) -> (Figure, Solution) {
    let mut robot = cases::case_s();
    robot.tendons[0].friction = Some(crate::model::tendon::Friction::pull(mu));
    let solution = solve(&robot);
    let mut style = Style::new("#000000");
    style.slack_tendons = true;
    style.tendon_colors = true;
    style.disks = Some(12);
    let mut figure = Figure::new("case S");
    figure.add_shape(&robot, &solution, &style);
    figure.legend = solved_shape_legend(&robot, &solution, &style);
    (figure, solution)
}

#[test]
fn a_tendon_with_friction_is_labelled_with_its_input_and_delivered_tension() {
    let (figure, solution) = case_s_with_friction(0.1);
    let svg = figure.to_svg();
    let state = solution.tendons[0];
    // S with mu = 0.1 delivers 2.550 N of its 2.94 N (docs/friction.md, "Issue 24 as a user
    // finds it"): the legend gives both, from the solution.
    assert_eq!(significant(state.delivered_tension), "2.55");
    let entry = &figure.legend[1];
    assert_eq!(entry.symbol, Symbol::Ramp);
    assert_eq!(
        entry.label,
        format!(
            "tendon 1 (line darker and wider where the tension is higher): straight at (8, 0) mm; friction 0.1, pulled in: {} N at the base -> {} N delivered",
            significant(state.tension),
            significant(state.delivered_tension)
        )
    );
    // The label is wrapped in the SVG; its last words are on one line.
    assert!(svg.contains("2.94 N at the base -&gt; 2.55 N delivered"), "{svg}");
    // The slack tendons keep their entries.
    assert_eq!(
        figure.legend[2].label,
        "tendon 2 (thin dashed line): straight at (0, 8) mm; slack (0 N)"
    );
}

#[test]
fn a_tendon_with_friction_is_drawn_lighter_and_thinner_where_its_tension_falls() {
    let (figure, solution) = case_s_with_friction(0.1);
    // Tendon 1's pieces come first, up to the first slack (dashed) tendon.
    let pieces: Vec<&Curve> = figure.panels[0]
        .curves
        .iter()
        .take_while(|c| c.dash.is_none())
        .collect();
    assert!(pieces.len() >= 10, "{}", pieces.len());
    // One hue, lighter toward the termination: the sum of the red, green and blue bytes
    // never falls, and the last piece is the lightest shade of the tendon's colour.
    let lightness = |c: &Curve| {
        (1..7)
            .step_by(2)
            .map(|k| u32::from_str_radix(&c.color[k..k + 2], 16).unwrap())
            .sum::<u32>()
    };
    for pair in pieces.windows(2) {
        assert!(
            lightness(pair[1]) >= lightness(pair[0]),
            "{} {}",
            pair[0].color,
            pair[1].color
        );
    }
    let lightest = tension::lighter(PALETTE[0], tension::LIGHTEST);
    assert!(lightness(pieces[0]) < lightness(pieces.last().unwrap()));
    // 12: within a few units of each byte of the lightest shade (the last piece's middle
    // lies half a piece before the termination).
    let end = Curve {
        color: lightest,
        ..pieces[0].clone()
    };
    assert!(lightness(&end) - lightness(pieces.last().unwrap()) < 12);
    // Pulled in: the tension falls from the base, so every piece is thinner than the last,
    // and the width follows tau / tau_max.
    for pair in pieces.windows(2) {
        assert!(pair[1].width < pair[0].width, "{} {}", pair[0].width, pair[1].width);
        assert_eq!(pair[0].points.last(), pair[1].points.first());
    }
    let delivered = solution.tendons[0].delivered_tension / solution.tendons[0].tension;
    let last = pieces.last().unwrap().width / tension::FRICTION_WIDTH;
    // The last piece is drawn at the tension of its middle, within 1 % of the end's (the
    // tension falls 13 % over the whole tendon, 40 pieces).
    assert!((last - delivered).abs() < 0.01, "{last} {delivered}");
    // The path drawn is the whole tendon: from its base entry to its termination.
    let whole = tendon_path(&cases::case_s(), &solution, 0);
    assert_eq!(pieces[0].points[0], whole[0]);
    assert_eq!(pieces.last().unwrap().points.last(), whole.last());
}

#[test]
fn frictionless_tendons_are_drawn_and_labelled_as_before() {
    let robot = cases::case_s();
    let solution = solve(&robot);
    let mut style = Style::new("#000000");
    style.slack_tendons = true;
    style.tendon_colors = true;
    let mut figure = Figure::new("case S");
    figure.add_shape(&robot, &solution, &style);
    // The tendons as the code before friction shading drew them: one curve each, thin,
    // solid when pulled and dashed when slack.
    for (i, tendon) in robot.tendons.iter().enumerate() {
        let pulled = tendon.tension() > 0.0;
        let before = Curve {
            points: tendon_path(&robot, &solution, i),
            color: PALETTE[i].to_string(),
            width: if pulled { shape::TENDON_WIDTH } else { 1.0 },
            dash: (!pulled).then(|| shape::SLACK_DASH.to_string()),
            opacity: if pulled { 0.9 } else { 0.8 },
        };
        assert_eq!(figure.panels[0].curves[i], before, "tendon {}", i + 1);
    }
    assert_eq!(figure.panels[0].curves.len(), robot.tendons.len() + 1);
    // The legend of the solved shape is the robot's, so the SVG is byte for byte the same.
    let before = {
        let mut f = figure.clone();
        f.legend = shape_legend(&robot, &style);
        f.to_svg()
    };
    figure.legend = solved_shape_legend(&robot, &solution, &style);
    assert_eq!(figure.to_svg(), before);
    // A coefficient of 0 is the frictionless tendon (solved bit for bit as without one).
    let (zero, _) = case_s_with_friction(0.0);
    assert_eq!(zero.to_svg(), case_s_figure().to_svg());
}

#[test]
fn tendons_in_the_shapes_colour_are_lines_even_with_friction() {
    let mut robot = cases::case_s();
    robot.tendons[0].friction = Some(crate::model::tendon::Friction::pull(0.1));
    let solution = solve(&robot);
    // A sweep's shapes: every tendon in the shape's colour, described by no legend entry.
    let style = Style::new("#9a9a9a");
    let mut panel = Panel::default();
    panel.add_shape(&robot, &solution, &style);
    assert_eq!(panel.curves.len(), 2, "tendon 1 and the backbone");
    assert_eq!(panel.curves[0].width, shape::TENDON_WIDTH);
    assert_eq!(panel.curves[0].color, "#9a9a9a");
    let legend = solved_shape_legend(&robot, &solution, &style);
    assert_eq!(legend, shape_legend(&robot, &style));
}
