//! The march of a history step's stick/slip pattern along a shape (docs/friction.md
//! section 8): each tendon with friction from its base entry, link by link, sliding or
//! sticking as its 1-D Coulomb problem on that shape says (module docs of [`super`]), then
//! slip zones inside the stuck stretch where friction cannot hold it ([`super::zone`]).

use super::*;

/// A node's stuck tension as a slip zone's balance reads it: its value on the shape (N), its
/// derivatives where read, the node's tension the shape was solved with (N), and, where
/// the node's joint solve coupled it to other tendons that stick there
/// ([`cross::couple`]), its gain with them answering: then the value is the joint
/// answer's, at which the node's tension is the stuck one.
type Seen = (f64, Option<Stuck>, f64, Option<f64>);

/// The march of every tendon with friction along the shape `x` (module docs): new contacts,
/// multipliers and predicted log tensions written into `border`'s profile and unknowns.
/// A link within `tie` (log tension, [`grip::tie`]) of its friction limit sticks. At `rest`
/// (the first step, [`Carried::rest`]) a loaded tendon is pulled in from slack: its material
/// holds no stuck tension, so it slides in on every link. On a shape not `converged` for
/// this step (the last step's, solved with the base tensions `solved`), a stuck tension is
/// moved by the other tendons' changes of base tension since ([`cross::stuck_moved`]).
/// Each link's capacity and stuck tension are those of its evaluation at `x`, the profile's
/// log tensions and contacts: when Newton has just `converged` to `x`, its last evaluation
/// of every link (kept by the profile) is that one and is read, else the link is evaluated.
/// Returns whether anything changed.
///
/// # Errors
/// A model breakdown on a link; a rigid tendon that would stick (statically
/// indeterminate).
pub(super) fn march(
    border: &mut Capstan,
    x: &[State],
    converged: bool,
    tie: f64,
    rest: bool,
    solved: &[f64],
) -> Result<bool> {
    let system = &border.system;
    let length = system.model.robot.length();
    let Some(profile) = system.friction.as_ref() else {
        return Ok(false);
    };
    let count = profile.count();
    let last = profile.spans.iter().copied().max().unwrap_or(0);
    let mut grips = profile.grips.clone().unwrap_or_default();
    let mut z = profile.z.clone();
    let mut changed = false;
    // A tendon slides from its base entry one way (the first link's) and, from the first
    // link that does not (stick, or the other way), sticks to its termination: a stretch
    // that slid beyond a stuck one would carry material past it (section 8).
    let mut stuck = vec![false; count];
    // Whether slip j's stuck tension is moved by the others on the first march of a step
    // (off the last step's converged shape): when a tendon other than slip j has a new base
    // tension, and whenever more than one tendon is loaded, even if no input changed (the
    // `stuck_moved` path then carries each stuck tension to its own fixed point alone).
    let tendons = &system.model.robot.tendons;
    let loaded = profile.base.iter().filter(|&&b| b > 0.0).count();
    let others_moved: Vec<bool> = (0..count)
        .map(|j| {
            !converged
                && (loaded > 1
                    || tendons
                        .iter()
                        .enumerate()
                        .any(|(l, t)| l != profile.slipping[j] && t.tension() != solved[l]))
        })
        .collect();
    let mut sliding: Vec<Option<Contact>> = vec![None; count];
    // Each slip's stuck tension at the link's end, as read (with its derivatives) and as
    // chosen with.
    let mut read: Vec<Option<Stuck>> = vec![None; count];
    let mut stuck_at = vec![0.0; count];
    let mut coupled: Vec<Option<f64>> = vec![None; count];
    // On a converged shape with two or more tendons with friction, the links each slip had
    // in a slip zone inside its stuck stretch on the pattern Newton solved with (any
    // sliding link after the base zone's run): the node's joint solve holds its tension
    // there ([`cross::Before`]'s `held`).
    let in_zone: Vec<Vec<bool>> = match profile.grips.as_ref() {
        Some(old) if converged && count > 1 => old.iter().map(|grip| zone::in_zone(&grip.contacts)).collect(),
        _ => vec![Vec::new(); count],
    };
    // Per slip and node, what a slip zone's balance reads of the stuck tension
    // ([`zone::Predictor`]): the stuck tension on the shape, its derivatives where read,
    // and the tension the shape was solved with there.
    let mut seen: Vec<Vec<Option<Seen>>> = vec![vec![None; last + 1]; count];
    // Off a converged shape, runs of four links within the spans evaluated at once where
    // the lanes take them (`System::friction_group`: each link with the one-link
    // kernel's bits), each evaluation handed back to the profile's spares once read.
    let mut group: Option<(usize, [Option<IntervalLinearization>; 4])> = None;
    for k in 0..last {
        let Some(sites) = system.interval_sites(k) else {
            continue;
        };
        let seg = system.mesh.nodes[k].segment_end;
        let kept = if converged {
            profile.cached(k, |lin| lin.map(|l| (l.capacity.clone(), l.stuck_tension.clone())))
        } else {
            None
        };
        let (capacities, stuck_tensions) = match kept {
            Some(kept) => kept,
            None => {
                let grouped = match &mut group {
                    Some((first, lins)) if (*first..*first + 4).contains(&k) => lins[k - *first].take(),
                    _ if k + 4 <= last => match system.friction_group(profile, k, x, None) {
                        Ok(Some(lins)) => {
                            let mut lins = lins.map(Some);
                            let first = lins[0].take();
                            group = Some((k, lins));
                            first
                        }
                        // Declined, or a breakdown in the four: link by link, which meets
                        // it where the march would.
                        _ => None,
                    },
                    _ => None,
                };
                let lin = match grouped {
                    Some(lin) => lin,
                    None => interval(profile, length, k, sites, seg, &x[k], &x[k + 1], None)?,
                };
                let read = (lin.capacity.clone(), lin.stuck_tension.clone());
                profile.give_link(lin);
                read
            }
        };
        // On a converged shape the stuck tension is read at the tension the stick row would
        // settle on, not the one the shape was solved with (`stuck_own`): a link's own
        // tension moves its stuck tension about 30 times as much the other way, so a choice
        // from the solved one alternates between sliding in and out; and another loaded
        // tendon's choice moves it by a gain of the same size ([`cross::couple`]).
        read.fill(None);
        for j in (0..count).filter(|&j| profile.on_link(j, k) && !rest) {
            let base = profile.base[j];
            stuck_at[j] = if converged && base > 0.0 {
                let at = profile.stuck_tension(j, k + 1, &sites.end, &x[k + 1], length);
                let own = profile.stuck_own(
                    j,
                    k + 1,
                    &sites.end,
                    &(stuck_tensions[j], at.1, at.2),
                    base * z[j][k + 1].exp(),
                );
                read[j] = Some(at);
                own
            } else if base > 0.0 && others_moved[j] {
                let at = profile.stuck_tension(j, k + 1, &sites.end, &x[k + 1], length);
                let moved = cross::stuck_moved(
                    profile,
                    j,
                    k + 1,
                    &sites.end,
                    &x[k + 1],
                    &(stuck_tensions[j], at.1, at.2),
                    solved,
                );
                read[j] = Some(at);
                moved
            } else {
                stuck_tensions[j]
            };
        }
        if count > 1 {
            let before: Vec<cross::Before> = (0..count)
                .map(|j| cross::Before {
                    za: z[j][k],
                    capacity: capacities[j],
                    solved: if converged {
                        profile.base[j]
                    } else {
                        solved[profile.slipping[j]]
                    } * z[j][k + 1].exp(),
                    stuck: stuck[j],
                    first: sliding[j],
                    on: profile.on_link(j, k),
                    held: in_zone[j].get(k).copied().unwrap_or(false),
                })
                .collect();
            coupled.fill(None);
            cross::couple(
                profile,
                &sites.end,
                &x[k + 1],
                &read,
                &before,
                &mut stuck_at,
                &mut coupled,
            );
        }
        for j in (0..count).filter(|&j| profile.on_link(j, k)) {
            let (base, za, capacity) = (profile.base[j], z[j][k], capacities[j]);
            let mut choice = choose(base, za, capacity, stuck_at[j], tie);
            let first = *sliding[j].get_or_insert(choice.contact);
            seen[j][k + 1] = Some(match coupled[j] {
                Some(gain) if converged => (stuck_at[j], None, stuck_at[j], Some(gain)),
                _ if converged => (stuck_tensions[j], read[j], base * z[j][k + 1].exp(), None),
                _ => (stuck_at[j], None, stuck_at[j], None),
            });
            if base > 0.0 && (stuck[j] || choice.contact != first) {
                choice.contact = Contact::Stick;
                choice.multiplier = stuck_multiplier(za, choice.zeta, capacity);
            }
            let zb = match choice.contact {
                Contact::Stick => {
                    let i = profile.slipping[j];
                    if system.model.robot.tendons[i].stiffness.is_none() {
                        return Err(rigid(i, x[k + 1].s));
                    }
                    if !choice.zeta.is_finite() {
                        return Err(slack(i, x[k + 1].s));
                    }
                    stuck[j] = true;
                    choice.zeta
                }
                _ if base == 0.0 => 0.0,
                _ => za + choice.multiplier * capacity,
            };
            let grip = &mut grips[j];
            changed |= !converged
                && choice.contact == Contact::Stick
                && (grip.capacities[k] - capacity).abs() > SETTLED * capacity;
            grip.contacts[k] = choice.contact;
            grip.multipliers[k] = choice.multiplier;
            grip.capacities[k] = capacity;
            z[j][k + 1] = zb;
        }
    }
    // Slip zones inside the stuck stretches, where a stuck link's multiplier leaves the
    // friction cone beyond the slip check's `CONE` (within it the stuck stretch is
    // answered as before) ([`zone`]), on a converged shape only: on a guess (a step's or a split
    // level's first march) a stuck link may leave the cone where the answer does not, and a
    // zone opened there changes the passes of steps that end without one.
    for (j, grip) in grips.iter_mut().enumerate() {
        let span = profile.spans[j];
        let steep = grip.contacts[..span].iter().enumerate().any(|(k, &c)| {
            c == Contact::Stick && (z[j][k + 1] - z[j][k]).abs() > grip.capacities[k] * (1.0 + slip::CONE)
        });
        let i = profile.slipping[j];
        let (Some(stiffness), true) = (system.model.robot.tendons[i].stiffness, steep && !rest && converged) else {
            continue;
        };
        let predictors: Vec<Option<zone::Predictor>> = (0..=span)
            .map(|n| {
                // The base entry's stuck tension is read only here (a zone that starts
                // inside the first link counts its material's change there).
                if n == 0 {
                    let sites = system.interval_sites(0)?;
                    let at = profile.stuck_tension(j, 0, &sites.start, &x[0], length);
                    let gain = if converged {
                        profile.own_gain(j, 0, &sites.start, &at).unwrap_or(0.0)
                    } else {
                        0.0
                    };
                    let solved = profile.base[j] * z[j][0].exp();
                    return Some(zone::Predictor {
                        value: at.0,
                        gain,
                        solved,
                    });
                }
                let (value, read, solved, coupled) = seen[j][n]?;
                let gain = match (coupled, read, n.checked_sub(1).and_then(|k| system.interval_sites(k))) {
                    (Some(gain), _, _) => gain,
                    (None, Some(read), Some(sites)) => profile.own_gain(j, n, &sites.end, &read).unwrap_or(0.0),
                    _ => 0.0,
                };
                Some(zone::Predictor { value, gain, solved })
            })
            .collect();
        let s: Vec<f64> = x[..=span].iter().map(|n| n.s).collect();
        let Grip {
            contacts,
            multipliers,
            capacities,
            reference,
            ..
        } = grip;
        // Off a converged shape a zone the march cannot resolve is left stuck where it
        // failed: the march on the converged shape decides (the slip check refuses what
        // stays outside the cone).
        let opened = zone::open(
            i,
            &mut zone::Tendon {
                contacts: &mut contacts[..span],
                multipliers: &mut multipliers[..span],
                capacities: &capacities[..span],
                z: &mut z[j][..=span],
                predictors: &predictors,
                reference: &reference[..=span],
                s: &s,
                stiffness,
                base: profile.base[j],
                first: sliding[j],
                tie,
            },
        );
        if converged {
            opened?;
        }
    }
    // Slip zones of two tendons on one link: the march solves each zone's balance alone.
    if converged && count > 1 {
        let s: Vec<f64> = x.iter().map(|n| n.s).collect();
        zone::overlap(&grips, &profile.spans, &profile.slipping, &s)?;
    }
    // What changed: a contact, or a transition link's multiplier beyond the tie.
    if let Some(old) = profile.grips.as_ref() {
        for (new, old) in grips.iter().zip(old) {
            for k in 0..new.contacts.len() {
                changed |= new.contacts[k] != old.contacts[k]
                    || (new.contacts[k] != Contact::Stick
                        && (new.multipliers[k] - old.multipliers[k]).abs() * new.capacities[k] > tie);
            }
        }
    }
    if let Some(p) = border.system.friction.as_mut() {
        for (j, &span) in p.spans.iter().enumerate() {
            for n in span + 1..z[j].len() {
                z[j][n] = z[j][span];
            }
        }
        p.z = z;
        p.grips = Some(grips);
    }
    border.reload();
    Ok(changed)
}
