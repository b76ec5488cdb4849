//! A step whose inputs repeat the last one's (docs/friction.md section 8, "A repeated
//! step"): the last answer held, every loaded tendon with friction stuck all along.

use super::super::grip::stuck_multiplier;
use super::Carried;
use crate::collocation::friction::*;
use crate::model::length;

/// Holds the last step's answer as the answer of a step whose inputs equal its own
/// (docs/friction.md section 8, "A repeated step"): `robot` with the tensions of that
/// answer. Nothing is driven, so nothing slides: every tendon with friction that carries
/// tension is stuck all along, at the tension it has, and the material it leaves is the
/// last step's (`carried` keeps it). What changes is the pattern the step's stability
/// verdict holds, rewritten in `carried.settled`: every link stuck, with the multiplier its
/// log tensions give and the material at the answer as its stick rows' (so the rows hold
/// there exactly). Returns false, and changes nothing, where a stuck tendon is rigid (its
/// stuck tension is indeterminate: the step is solved, and the march refuses it).
pub(crate) fn hold_last(robot: &Robot, carried: &mut Carried) -> bool {
    let Some(settled) = carried.settled.as_mut() else {
        return false;
    };
    let model = Model::new(robot);
    let profile = Profile::new(&model, &settled.mesh);
    let loaded = |j: usize| profile.base[j] > 0.0;
    if (0..profile.count()).any(|j| loaded(j) && robot.tendons[profile.slipping[j]].stiffness.is_none()) {
        return false;
    }
    let length = robot.length();
    for (j, grip) in settled.grips.iter_mut().enumerate().filter(|&(j, _)| loaded(j)) {
        let (i, span, base) = (profile.slipping[j], profile.spans[j], profile.base[j]);
        let tendon = &robot.tendons[i];
        let z = &settled.z[j];
        for k in 0..span {
            grip.contacts[k] = Contact::Stick;
            grip.multipliers[k] = stuck_multiplier(z[k], z[k + 1], grip.capacities[k]);
        }
        for (n, node) in settled.x[..=span].iter().enumerate() {
            let speed = length::speed(&tendon.routing.at(node.s, length), &node.v, &node.u);
            grip.reference[n] = tendon
                .stiffness
                .map_or(speed, |e| speed / (1.0 + base * z[n].exp() / e));
        }
    }
    // Every link's multiplier is the constant one its capacity gives.
    settled.shares.clear();
    true
}
