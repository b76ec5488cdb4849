//! What a system's sites are computed from ([`SiteInputs`]): kept with the sites in a workspace's buffers, so that the next system on
//! the same mesh of a robot whose sites would be the same bit for bit (the next row of a
//! batch, the next step of a sweep: only the tensions changed) takes them instead of
//! computing them again.

use super::{System, SystemBuffers};
use crate::mesh::Mesh;
use crate::model::equations::Model;
use crate::model::loads::Field;
use crate::model::robot::RodModel;
use crate::model::rod::{ReferenceStrains, Rod, Section, Stiffness};
use nalgebra::Vector3;
use std::sync::Arc;

/// The inputs of the sites of a system, as numbers: the model's load factor and traced
/// parameter's value, the mesh's nodes (arc length and segment end), the rod's stiffness
/// and reference strains, the distributed force, moment and follower force, and the rod
/// model; bits for values, the address for a user function (the traced parameter's kind is
/// [`super::SystemBuffers::has_sites_of`]'s to compare).
/// The rod and the three fields whose numbers they are stay held here, so that an address
/// recorded names the same function as long as it is compared.
#[derive(Default)]
pub(crate) struct SiteInputs {
    numbers: Vec<u64>,
    held: Option<(Rod, [Field; 3])>,
}

impl SiteInputs {
    /// Whether these are the inputs of the sites of `model` on `mesh`, bit for bit (none
    /// recorded: false).
    pub(crate) fn are_of(&self, model: &Model, mesh: &Mesh) -> bool {
        if self.held.is_none() {
            return false;
        }
        let mut kept = self.numbers.iter();
        let same = each_number(model, mesh, |x| kept.next() == Some(&x));
        same && kept.next().is_none()
    }

    /// Records the inputs of the sites of `model` on `mesh`, unless they are these already
    /// (which keeps the rod and fields held).
    pub(crate) fn record(&mut self, model: &Model, mesh: &Mesh) {
        if self.are_of(model, mesh) {
            return;
        }
        self.numbers.clear();
        let numbers = &mut self.numbers;
        each_number(model, mesh, |x| {
            numbers.push(x);
            true
        });
        let robot = model.robot;
        let loads = &robot.loads;
        self.held = Some((
            robot.rod.clone(),
            [
                loads.distributed_force.clone(),
                loads.distributed_moment.clone(),
                loads.follower_distributed_force.clone(),
            ],
        ));
    }
}

impl<'a> System<'a> {
    /// The system of a copy of `model` on `mesh`, its sites and the copy's tensions written
    /// into `buffers` (a workspace's, [`System::into_parts`]) instead of new ones.
    /// The sites are kept when the buffers' are those of `model` on `mesh` bit for bit
    /// (a batch's next row: only the tensions changed).
    pub(crate) fn with_buffers(model: &Model<'a>, mesh: Mesh, buffers: SystemBuffers) -> Self {
        let model = model.clone_in(buffers.tensions);
        let buffers = SystemBuffers {
            tensions: Vec::new(),
            ..buffers
        };
        match buffers.has_sites_of(&model, &mesh) && buffers.inputs.are_of(&model, &mesh) {
            true => System::with_kept_sites(model, mesh, buffers),
            false => System::assembled(model, mesh, buffers),
        }
    }
}

/// Passes every number of the inputs of the sites of `model` on `mesh` to `f`, in a fixed
/// order (each variant's tag before its numbers), until `f` returns false; whether it never
/// did.
fn each_number(model: &Model, mesh: &Mesh, mut f: impl FnMut(u64) -> bool) -> bool {
    let robot = model.robot;
    let vector = |f: &mut dyn FnMut(u64) -> bool, v: &Vector3<f64>| v.iter().all(|x| f(x.to_bits()));
    let section =
        |f: &mut dyn FnMut(u64) -> bool, s: &Section| s.kse.iter().chain(s.kbt.iter()).all(|x| f(x.to_bits()));
    let factors = f(model.load_factor.to_bits()) && f(model.parameter.map_or(0, |(_, value)| value.to_bits()));
    let mesh_nodes = factors
        && f(mesh.nodes.len() as u64)
        && mesh
            .nodes
            .iter()
            .all(|n| f(n.s.to_bits()) && f(n.segment_end.to_bits()));
    let stiffness = mesh_nodes
        && match &robot.rod.stiffness {
            Stiffness::Uniform(s) => f(0) && section(&mut f, s),
            Stiffness::Varying(g) => f(1) && f(Arc::as_ptr(g) as *const () as usize as u64),
            Stiffness::Segments { ends, sections } => {
                f(2) && f(ends.len() as u64)
                    && ends.iter().all(|e| f(e.to_bits()))
                    && sections.iter().all(|s| section(&mut f, s))
            }
        };
    let reference = stiffness
        && match &robot.rod.reference {
            ReferenceStrains::Straight => f(0),
            ReferenceStrains::Constant { v_star, u_star } => f(1) && vector(&mut f, v_star) && vector(&mut f, u_star),
            ReferenceStrains::Varying(g) => f(2) && f(Arc::as_ptr(g) as *const () as usize as u64),
            ReferenceStrains::Segments { ends, u_star } => {
                f(3) && f(ends.len() as u64)
                    && ends.iter().all(|e| f(e.to_bits()))
                    && u_star.iter().all(|u| vector(&mut f, u))
            }
        };
    let loads = &robot.loads;
    let fields = [
        &loads.distributed_force,
        &loads.distributed_moment,
        &loads.follower_distributed_force,
    ];
    reference
        && fields.iter().all(|field| match field {
            Field::Constant(v) => f(0) && vector(&mut f, v),
            Field::Varying(g) => f(1) && f(Arc::as_ptr(g) as *const () as usize as u64),
        })
        && f(u64::from(robot.rod_model == RodModel::Kirchhoff))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Robot;
    use crate::model::loads::Loads;

    /// The inputs recorded for a model on a mesh are its own only: another tension keeps
    /// them, one unit in the last place of a node, of the stiffness, of the distributed
    /// force or of the load factor, another user function (even an equal one), or the
    /// Kirchhoff model do not.
    #[test]
    fn inputs_are_those_of_the_same_sites_only() {
        let robot = crate::cases::prototype();
        let mesh = Mesh::uniform(&robot, 16).unwrap();
        let mut inputs = SiteInputs::default();
        let same = |inputs: &SiteInputs, robot: &Robot, mesh: &Mesh| inputs.are_of(&Model::new(robot), mesh);
        assert!(!same(&inputs, &robot, &mesh));
        inputs.record(&Model::new(&robot), &mesh);
        assert!(same(&inputs, &robot, &mesh));
        let mut pulled = robot.clone();
        pulled.tendons[1].set_tension(2.5);
        assert!(same(&inputs, &pulled, &mesh));
        let mut loaded = Model::new(&robot);
        loaded.load_factor = f64::from_bits(1f64.to_bits() - 1);
        assert!(!inputs.are_of(&loaded, &mesh));

        let next = |x: f64| f64::from_bits(x.to_bits() + 1);
        let mut moved = mesh.clone();
        moved.nodes[3].s = next(moved.nodes[3].s);
        assert!(!same(&inputs, &robot, &moved));
        assert!(!same(&inputs, &robot, &Mesh::uniform(&robot, 17).unwrap()));
        let mut stiffer = robot.clone();
        if let Stiffness::Uniform(s) = &mut stiffer.rod.stiffness {
            s.kbt[2] = next(s.kbt[2]);
        }
        assert!(!same(&inputs, &stiffer, &mesh));
        let mut heavier = robot.clone();
        heavier.loads.distributed_force = Field::Constant(heavier.loads.distributed_force.at(0.0).map(next));
        assert!(!same(&inputs, &heavier, &mesh));
        let mut kirchhoff = robot.clone();
        kirchhoff.rod_model = RodModel::Kirchhoff;
        assert!(!same(&inputs, &kirchhoff, &mesh));

        // A user function is its own: the same one (a clone) keeps the inputs, an equal one
        // made apart does not.
        let weight = robot.loads.distributed_force.at(0.0);
        let with_function = |robot: &Robot| {
            let mut r = robot.clone();
            r.loads = Loads {
                distributed_force: Field::Varying(Arc::new(move |_| weight)),
                ..robot.loads.clone()
            };
            r
        };
        let varying = with_function(&robot);
        inputs.record(&Model::new(&varying), &mesh);
        assert!(same(&inputs, &varying.clone(), &mesh));
        assert!(!same(&inputs, &with_function(&robot), &mesh));
        assert!(!same(&inputs, &robot, &mesh));
    }

    /// A system built in the buffers of another system on the same mesh has its own sites,
    /// bit for bit those of a system built afresh: recomputed after the prototype for the
    /// prototype with 1.5 times its self weight and a 1.2 times stiffer one (stale sites
    /// would be the prototype's), kept for one with other tensions.
    #[test]
    fn a_system_in_kept_buffers_has_its_own_sites() {
        use crate::collocation::system::System;
        let base = crate::cases::prototype();
        let mut heavier = base.clone();
        heavier.loads.distributed_force = Field::Constant(base.loads.distributed_force.at(0.0) * 1.5);
        let mut stiffer = base.clone();
        let Stiffness::Uniform(section) = &mut stiffer.rod.stiffness else {
            panic!("the prototype's section is uniform");
        };
        section.kbt *= 1.2;
        let mut pulled = base.clone();
        pulled.tendons[1].set_tension(1.0);
        let mesh = Mesh::uniform(&base, 16).unwrap();
        let sites = |system: &System| format!("{:?} {:?}", system.node_sites, system.interval_sites);
        let (_, mut buffers) = System::new(Model::new(&base), mesh.clone()).into_parts();
        let base_sites = sites(&System::new(Model::new(&base), mesh.clone()));
        for (robot, same_sites) in [(&heavier, false), (&stiffer, false), (&pulled, true), (&base, true)] {
            let model = Model::new(robot);
            let system = System::with_buffers(&model, mesh.clone(), buffers);
            let own = sites(&System::new(Model::new(robot), mesh.clone()));
            assert_eq!(sites(&system), own);
            // The prototype's sites (left in the buffers) would not do for the first two.
            assert_eq!(own == base_sites, same_sites);
            buffers = system.into_parts().1;
        }
    }
}
