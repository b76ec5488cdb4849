//! The sites at a quarter and three quarters of every interval ([`QuarterSites`]), which
//! only the order-6 estimate reads: computed the first time it needs them on a system's
//! sites, and kept with those sites in a workspace's buffers, so that the next system that
//! keeps the sites (the same inputs, [`super::inputs::SiteInputs`]: a batch's next row)
//! keeps them too.

use super::System;
use crate::collocation::residual::{IntervalSites, QuarterSites};
use crate::model::equations::Model;
use std::sync::{Mutex, OnceLock};

/// Each link's [`QuarterSites`] (`None` for a jump), once computed from the model and the
/// interval sites they belong to; the buffer of those forgotten, for the next. Both are
/// thread-safe (a `Solver` is shared across threads, Python's included); the lock is taken
/// only when the sites are computed.
#[derive(Default)]
pub(super) struct Quarters {
    sites: OnceLock<Vec<Option<QuarterSites>>>,
    spare: Mutex<Vec<Option<QuarterSites>>>,
}

impl Quarters {
    /// Each link's quarter sites on `interval_sites` (the sites of `model` on its mesh),
    /// computed now unless they were since the last [`Quarters::forget`].
    fn of(&self, model: &Model, interval_sites: &[Option<IntervalSites>]) -> &[Option<QuarterSites>] {
        self.sites.get_or_init(|| {
            // A poisoned lock holds only a buffer: take it all the same.
            let mut quarters = std::mem::take(&mut *self.spare.lock().unwrap_or_else(|e| e.into_inner()));
            quarters.clear();
            quarters.extend(interval_sites.iter().map(|sites| {
                sites.as_ref().map(|sites| {
                    let h = sites.end.s - sites.start.s;
                    QuarterSites {
                        quarter: model.site(sites.start.s + 0.25 * h),
                        three_quarters: model.site(sites.start.s + 0.75 * h),
                    }
                })
            }));
            quarters
        })
    }

    /// Forgets the quarter sites (the sites they were computed on are recomputed), keeping
    /// their buffer.
    pub(super) fn forget(&mut self) {
        if let Some(quarters) = self.sites.take() {
            *self.spare.get_mut().unwrap_or_else(|e| e.into_inner()) = quarters;
        }
    }

    /// Whether the quarter sites are computed (for the tests).
    #[cfg(test)]
    fn computed(&self) -> bool {
        self.sites.get().is_some()
    }
}

impl System<'_> {
    /// The sites at a quarter and three quarters of interval k (computed for every
    /// interval the first time one is asked for, then kept with the sites).
    pub(super) fn quarters(&self, k: usize) -> &QuarterSites {
        match &self.quarters.of(&self.model, &self.interval_sites)[k] {
            Some(quarters) => quarters,
            None => unreachable!("link {k} is a jump: only an interval's rows ask for its quarter sites"),
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::collocation::system::System;
    use crate::mesh::Mesh;
    use crate::model::equations::Model;
    use crate::model::loads::Field;

    /// A system built in the buffers of another system whose quarter sites were computed
    /// has its own quarter sites, bit for bit those of a system built afresh: computed
    /// again for the prototype with 1.5 times its self weight (the prototype's, left in
    /// the buffers, would differ), kept (already computed when the system is built) for
    /// one with other tensions.
    #[test]
    fn kept_quarter_sites_are_those_of_a_fresh_system() {
        let base = crate::cases::prototype();
        let mut heavier = base.clone();
        heavier.loads.distributed_force = Field::Constant(base.loads.distributed_force.at(0.0) * 1.5);
        let mut pulled = base.clone();
        pulled.tendons[1].set_tension(1.0);
        let mesh = Mesh::uniform(&base, 16).unwrap();
        let quarters = |system: &System| {
            (0..mesh.nodes.len() - 1)
                .map(|k| format!("{:?}", system.quarters(k)))
                .collect::<Vec<_>>()
        };
        let first = System::new(Model::new(&base), mesh.clone());
        let base_quarters = quarters(&first);
        let (_, mut buffers) = first.into_parts();
        for (robot, kept) in [(&heavier, false), (&base, false), (&pulled, true), (&base, true)] {
            let system = System::with_buffers(&Model::new(robot), mesh.clone(), buffers);
            assert_eq!(system.quarters.computed(), kept);
            let own = quarters(&System::new(Model::new(robot), mesh.clone()));
            assert_eq!(quarters(&system), own);
            // The prototype's quarter sites would not do for the heavier robot.
            assert_eq!(own == base_quarters, !std::ptr::eq(robot, &heavier));
            buffers = system.into_parts().1;
        }
    }
}
