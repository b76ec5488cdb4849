//! A solved shape as drawing elements: the backbone and the tendon paths sampled from the
//! solution's dense interpolant, spacer disks, load arrows; legend labels for tendons (with
//! the turns each makes over its own length, [`Tendon::turns`]) and loads.

use super::axes::significant;
use super::tension;
use super::{Arrow, ArrowKind, Curve, Disk, LegendEntry, Marker, PALETTE, Panel, Style, Symbol};
use crate::model::routing::Routing;
use crate::model::tendon::Tendon;
use crate::{PointLoad, Robot, Solution};
use nalgebra::Vector3;

/// Points per metre of backbone or tendon drawn, at least [`MIN_SAMPLES`]: 1 mm spacing on
/// the prototype, far below a pixel's worth of Hermite interpolation error.
const SAMPLES_PER_METRE: f64 = 1000.0;
/// Fewest points drawn per backbone or tendon.
const MIN_SAMPLES: usize = 200;
/// Points per helix turn of a tendon path: a 5.6 degree chord, smooth at any size drawn.
const SAMPLES_PER_TURN: f64 = 64.0;
/// Small arrows drawn along the backbone for a distributed force.
const DISTRIBUTED_ARROWS: usize = 6;
/// Dash pattern of slack tendons.
pub(super) const SLACK_DASH: &str = "5 3";
/// Backbone stroke width (px).
pub(super) const BACKBONE_WIDTH: f64 = 2.2;
/// Stroke width of a pulled tendon (px).
pub(super) const TENDON_WIDTH: f64 = 1.2;
/// Disk colour.
pub(super) const DISK_COLOR: &str = "#6b6b6b";
/// Colour of the distributed-load arrows.
pub(super) const DISTRIBUTED_COLOR: &str = "#8a8a8a";
/// Colour of the tip-force and point-load arrows (Tol's wine: apart from every tendon and
/// tension colour).
pub const FORCE_COLOR: &str = "#882255";

/// A number of turns as legends write it: `1 turn`, `0.5 turns`, `-2 turns (left-handed)`.
pub fn turns_label(turns: f64) -> String {
    let number = significant(turns);
    let plural = if number == "1" || number == "-1" { "" } else { "s" };
    let hand = if turns < 0.0 { " (left-handed)" } else { "" };
    format!("{number} turn{plural}{hand}")
}

/// Tendon `index` (from 0) of `robot` as legends describe it, numbered from 1 as the command
/// line and robot files do: `tendon 5: ` and [`tendon_description`].
pub fn tendon_label(robot: &Robot, index: usize) -> String {
    format!("tendon {}: {}", index + 1, tendon_description(robot, index))
}

/// Tendon `index` (from 0) of `robot` without its number: [`routing_label`] and its
/// tension, `helix of radius 8 mm, 0.5 turns, ends at s = 121 mm; 4.91 N`.
pub fn tendon_description(robot: &Robot, index: usize) -> String {
    let tendon = &robot.tendons[index];
    let tension = if tendon.tension() > 0.0 {
        format!("{} N", significant(tendon.tension()))
    } else {
        "slack (0 N)".to_string()
    };
    format!("{}; {tension}", routing_label(tendon, robot.length()))
}

/// Where `tendon` runs on a rod of `length` L (m): its routing (offsets in mm), for a helix
/// the true number of turns over its own length ([`Tendon::turns`]), and where it ends if
/// before the tip: `helix of radius 8 mm, 0.5 turns, ends at s = 121 mm`.
pub fn routing_label(tendon: &Tendon, length: f64) -> String {
    let turns = tendon.turns(length);
    let routing = match &tendon.routing {
        Routing::Straight { x, y } => {
            // A component a billion times smaller than the offset is the rounding residue of
            // a computed cosine (0.008 cos(pi/2) = 4.9e-19 m), not a placement: shown as 0.
            let shown = |c: f64| if c.abs() < 1e-9 * x.hypot(*y) { 0.0 } else { c };
            format!("straight at ({}, {}) mm", mm(shown(*x)), mm(shown(*y)))
        }
        Routing::Helical { radius, .. } => {
            format!("helix of radius {} mm, {}", mm(*radius), turns_label(turns))
        }
        // 0.005 turns (1.8 degrees): less is not worth a word.
        Routing::Custom(_) if turns.abs() >= 0.005 => format!("custom routing, {}", turns_label(turns)),
        Routing::Custom(_) => "custom routing".to_string(),
    };
    let end = tendon.end(length);
    if end < length {
        format!("{routing}, ends at s = {} mm", mm(end))
    } else {
        routing
    }
}

/// A length (m) in millimetres, three significant digits.
fn mm(x: f64) -> String {
    significant(x * 1e3)
}

/// The largest tendon offset |r| (m) of the robot over each tendon's own length
/// ([`Routing::max_offset`]); 0 without tendons.
fn largest_offset(robot: &Robot) -> f64 {
    let length = robot.length();
    robot
        .tendons
        .iter()
        .map(|t| t.routing.max_offset(t.end(length), length))
        .fold(0.0, f64::max)
}

/// The number of spacer disks drawn when [`Style::disks`] is `None`: disks about 2.5
/// tendon offsets apart (the prototype's 12 disks, 20 mm apart for tendons 8 mm out, on
/// 242 mm), at least 1 and at most 60; none on a robot without tendons.
pub fn default_disks(robot: &Robot) -> usize {
    let offset = largest_offset(robot);
    if offset <= 0.0 {
        return 0;
    }
    ((robot.length() / (2.5 * offset)).round() as usize).clamp(1, 60)
}

/// The radius (m) spacer disks are drawn with: 1.25 times the largest tendon offset, so the
/// tendons run inside them; 4 % of the length without tendons.
pub fn disk_radius(robot: &Robot) -> f64 {
    let offset = largest_offset(robot);
    if offset > 0.0 {
        1.25 * offset
    } else {
        0.04 * robot.length()
    }
}

/// The point loads drawn as arrows: all but the weights of [`Style::placed_disks`], which
/// the disks' legend entry gives.
fn drawn_point_loads<'a>(robot: &'a Robot, style: &Style) -> &'a [PointLoad] {
    let all = &robot.loads.point[..];
    style.placed_disks.as_ref().and_then(|d| d.others(all)).unwrap_or(all)
}

/// The number of disks `style` draws on `robot`.
pub(super) fn disk_count(robot: &Robot, style: &Style) -> usize {
    match &style.placed_disks {
        Some(d) => d.positions.len(),
        None => style.disks.unwrap_or_else(|| default_disks(robot)),
    }
}

/// Where the disks `style` draws on `robot` sit (m) and their radius (m): the robot's own
/// ([`Style::placed_disks`]) or [`disk_count`] evenly spaced.
fn disk_places(robot: &Robot, style: &Style) -> (Vec<f64>, f64) {
    let radius = disk_radius(robot);
    match &style.placed_disks {
        Some(d) => (d.positions.clone(), d.radius.unwrap_or(radius)),
        None => {
            let (length, count) = (robot.length(), disk_count(robot, style));
            ((1..=count).map(|k| length * k as f64 / count as f64).collect(), radius)
        }
    }
}

/// Evenly spaced arc lengths from 0 to `end` (m), `count + 1` of them.
fn grid(end: f64, count: usize) -> impl Iterator<Item = f64> {
    (0..=count).map(move |k| end * k as f64 / count as f64)
}

/// The path of tendon `index`, p(s) + R(s) r(s) from s = 0 to its termination, sampled from
/// the solution's dense interpolant ([`Solution::at`]) densely enough that a helix is smooth.
pub fn tendon_path(robot: &Robot, solution: &Solution, index: usize) -> Vec<Vector3<f64>> {
    let tendon = &robot.tendons[index];
    let length = solution.length();
    let end = tendon.end(length).min(length);
    let turns = tendon.turns(length).abs();
    let count = ((end * SAMPLES_PER_METRE) as usize)
        .max(MIN_SAMPLES)
        .max((turns * SAMPLES_PER_TURN).ceil() as usize);
    grid(end, count)
        .enumerate()
        .map(|(k, s)| {
            // The last point is the left limit: the tendon ends there.
            let state = solution.at_limit(s, k == count);
            state.p + state.R * tendon.routing.at(s, length).r
        })
        .collect()
}

impl Panel {
    /// Adds a solved shape: the backbone sampled densely with [`Solution::at`], the tendon
    /// paths ([`tendon_path`]: thin, pulled ones solid, slack ones dashed if
    /// [`Style::slack_tendons`]; with [`Style::tendon_colors`], a pulled tendon with friction
    /// in pieces darker and wider where its tension is higher, [`solved_shape_legend`]),
    /// spacer disks ([`Style::disks`]), arrows for the tip force
    /// and point loads and small arrows for a distributed force ([`Style::loads`],
    /// [`Style::distributed_load`]), a square at the base and a dot at the tip.
    pub fn add_shape(&mut self, robot: &Robot, solution: &Solution, style: &Style) {
        let length = solution.length();
        for (i, tendon) in robot.tendons.iter().enumerate() {
            let pulled = tendon.tension() > 0.0;
            if !pulled && !style.slack_tendons {
                continue;
            }
            if let Some(profile) = tension::shaded(robot, solution, i, style, pulled) {
                let end = tendon.end(length).min(length);
                let color = tendon_color(style, i);
                let points = tendon_path(robot, solution, i);
                let opacity = 0.9 * style.opacity;
                self.curves
                    .extend(tension::pieces(&points, end, solution, i, &profile, color, opacity));
                continue;
            }
            self.curves.push(Curve {
                points: tendon_path(robot, solution, i),
                color: tendon_color(style, i).to_string(),
                width: if pulled { TENDON_WIDTH } else { 1.0 },
                dash: (!pulled).then(|| SLACK_DASH.to_string()),
                opacity: if pulled { 0.9 } else { 0.8 } * style.opacity,
            });
        }
        let count = ((length * SAMPLES_PER_METRE) as usize).max(MIN_SAMPLES);
        self.curves.push(Curve {
            points: grid(length, count).map(|s| solution.at(s).p).collect(),
            color: style.color.clone(),
            width: BACKBONE_WIDTH,
            dash: style.dash.clone(),
            opacity: style.opacity,
        });
        let (places, radius) = disk_places(robot, style);
        for s in places {
            let state = solution.at_limit(s, true);
            self.disks.push(Disk {
                center: state.p,
                rotation: state.R,
                radius,
            });
        }
        self.origin.get_or_insert(solution.base().p);
        self.markers.push(Marker {
            point: solution.tip().p,
            color: style.color.clone(),
            radius: 2.5,
        });
        if style.loads {
            let loads = &robot.loads;
            if loads.tip_force.norm() > 0.0 {
                self.arrows.push(Arrow {
                    point: solution.tip().p,
                    vector: loads.tip_force,
                    kind: ArrowKind::Force,
                    color: FORCE_COLOR.into(),
                    label: Some(format!("{} N", significant(loads.tip_force.norm()))),
                });
            }
            for load in drawn_point_loads(robot, style).iter().filter(|l| l.force.norm() > 0.0) {
                self.arrows.push(Arrow {
                    point: solution.at(load.s).p,
                    vector: load.force,
                    kind: ArrowKind::Force,
                    color: FORCE_COLOR.into(),
                    label: Some(format!("{} N", significant(load.force.norm()))),
                });
            }
        }
        if style.distributed_load {
            let arrows: Vec<(f64, Vector3<f64>)> = (0..DISTRIBUTED_ARROWS)
                .map(|k| length * (k as f64 + 0.5) / DISTRIBUTED_ARROWS as f64)
                .map(|s| (s, robot.loads.distributed_force.at(s)))
                .collect();
            let largest = arrows.iter().map(|(_, f)| f.norm()).fold(0.0, f64::max);
            if largest > 0.0 {
                // Label the largest arrow nearest the middle (away from the tip's labels).
                let middle = (DISTRIBUTED_ARROWS - 1) as f64 / 2.0;
                let labelled = (0..DISTRIBUTED_ARROWS)
                    .filter(|&k| arrows[k].1.norm() >= 0.99 * largest)
                    .min_by(|&a, &b| (a as f64 - middle).abs().total_cmp(&(b as f64 - middle).abs()))
                    .unwrap_or(0);
                for (k, (s, f)) in arrows.into_iter().enumerate() {
                    self.arrows.push(Arrow {
                        point: solution.at(s).p,
                        vector: f,
                        kind: ArrowKind::Distributed,
                        color: DISTRIBUTED_COLOR.into(),
                        label: (k == labelled).then(|| format!("{} N/m", significant(largest))),
                    });
                }
            }
        }
    }
}

/// The colour tendon `index` is drawn in.
pub(super) fn tendon_color(style: &Style, index: usize) -> &str {
    if style.tendon_colors {
        PALETTE[index % PALETTE.len()]
    } else {
        &style.color
    }
}

/// The legend of one shape drawn with `style` ([`Panel::add_shape`]): the backbone, every
/// tendon drawn ([`tendon_label`]: which one, its routing and true turns, its tension), the
/// spacer disks, and the loads with their magnitudes. It knows the robot only: for a robot
/// whose tendons have friction, [`solved_shape_legend`] also gives the tension each delivers.
pub fn shape_legend(robot: &Robot, style: &Style) -> Vec<LegendEntry> {
    legend(robot, None, style)
}

/// [`shape_legend`] for the shape `solution` of `robot`: a tendon with friction, which
/// [`Panel::add_shape`] draws darker and wider where its tension is higher when tendons
/// have their own colours ([`Style::tendon_colors`]), has an entry
/// with its friction, its motion, its tension at the base entry and the tension it delivers
/// at its termination (`...; friction 0.1, pulled in: 2.94 N at the base -> 2.55 N
/// delivered`); every other entry is [`shape_legend`]'s.
pub fn solved_shape_legend(robot: &Robot, solution: &Solution, style: &Style) -> Vec<LegendEntry> {
    legend(robot, Some(solution), style)
}

/// [`shape_legend`], with the entries of tendons with friction from `solution` if given.
fn legend(robot: &Robot, solution: Option<&Solution>, style: &Style) -> Vec<LegendEntry> {
    let mut legend = vec![LegendEntry::new(Symbol::Line, "backbone (thick line)", &style.color).width(BACKBONE_WIDTH)];
    for (i, tendon) in robot.tendons.iter().enumerate() {
        let pulled = tendon.tension() > 0.0;
        if !pulled && !style.slack_tendons {
            continue;
        }
        let profile = solution.and_then(|s| tension::shaded(robot, s, i, style, pulled));
        if let Some(profile) = profile {
            let routing = routing_label(tendon, robot.length());
            legend.push(tension::legend_entry(
                robot,
                i,
                &profile,
                &routing,
                tendon_color(style, i),
            ));
            continue;
        }
        let line = if pulled { "thin line" } else { "thin dashed line" };
        let entry = LegendEntry::new(
            Symbol::Line,
            &format!("tendon {} ({line}): {}", i + 1, tendon_description(robot, i)),
            tendon_color(style, i),
        );
        legend.push(if pulled {
            entry.width(TENDON_WIDTH)
        } else {
            entry.width(1.0).dash(SLACK_DASH)
        });
    }
    let disks = disk_count(robot, style);
    if disks > 0 {
        let placed = match &style.placed_disks {
            Some(d) => format!("{} N each", significant(d.weight.norm())),
            None => "evenly spaced".to_string(),
        };
        legend.push(LegendEntry::new(
            Symbol::Disk,
            &format!(
                "{disks} spacer disk{}, {placed} (drawn {} mm in radius)",
                if disks == 1 { "" } else { "s" },
                mm(disk_places(robot, style).1)
            ),
            DISK_COLOR,
        ));
    }
    let loads = &robot.loads;
    if style.loads && loads.tip_force.norm() > 0.0 {
        legend.push(LegendEntry::new(
            Symbol::Arrow,
            &format!(
                "tip force {} N (arrow length proportional to force)",
                significant(loads.tip_force.norm())
            ),
            FORCE_COLOR,
        ));
    }
    if style.loads {
        for load in drawn_point_loads(robot, style).iter().filter(|l| l.force.norm() > 0.0) {
            legend.push(LegendEntry::new(
                Symbol::Arrow,
                &format!(
                    "point load {} N at s = {} mm",
                    significant(load.force.norm()),
                    mm(load.s)
                ),
                FORCE_COLOR,
            ));
        }
    }
    if style.distributed_load {
        let length = robot.length();
        let largest = (0..=DISTRIBUTED_ARROWS)
            .map(|k| {
                loads
                    .distributed_force
                    .at(length * k as f64 / DISTRIBUTED_ARROWS as f64)
                    .norm()
            })
            .fold(0.0, f64::max);
        if largest > 0.0 {
            legend.push(LegendEntry::new(
                Symbol::Arrow,
                &format!("distributed force, up to {} N/m (small arrows)", significant(largest)),
                DISTRIBUTED_COLOR,
            ));
        }
    }
    legend
}
