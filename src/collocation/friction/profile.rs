//! The tension profile of the tendons with friction on a mesh ([`Profile`]): the log
//! tensions z_j = ln(tau_j / tau_j(0)) at the nodes of each tendon's span (z_j = 0 at the
//! base), a model to evaluate eq. 13 with friction at them, and the links' last
//! evaluations that the border and the next link reuse.
#![allow(non_snake_case)]

mod responses;
use super::grip::{Contact, Grip, Stuck, stuck_multiplier};
use super::interval::IntervalLinearization;
use crate::error::Result;
use crate::mesh::Mesh;
use crate::model::equations::{Model, Site};
use crate::model::friction::{self, FrictionLinearization};
use crate::solution::State;
use nalgebra::{Matrix3, SMatrix, Vector3, Vector6};
use std::cell::{Cell, RefCell};

/// The log tensions of the tendons with friction on a mesh, and a model to evaluate eq. 13
/// with them.
#[derive(Debug)]
pub(crate) struct Profile<'a> {
    /// Indices of the tendons with friction ([`friction::slipping`]).
    pub(crate) slipping: Vec<usize>,
    /// Their tensions at the base entry tau_j(0) (N), the input.
    pub(crate) base: Vec<f64>,
    /// The last node of each one's span (its left limit at the termination).
    pub(crate) spans: Vec<usize>,
    /// z_j at every node (0 at node 0; past the span, the span's last value).
    pub(crate) z: Vec<Vec<f64>>,
    /// In a stick/slip history, each slip's [`Grip`] on this mesh; None in full slip.
    pub(crate) grips: Option<Vec<Grip>>,
    /// The model with the tensions of one point, for eq. 13 with friction, and four
    /// copies of it (made at the first use) for four points at once.
    pub(super) scratch: RefCell<Model<'a>>,
    /// Four copies of `scratch`, one per lane of friction's four links at once.
    pub(super) quad: RefCell<Vec<Model<'a>>>,
    /// Each link's last evaluation ([`interval`] through the system's residual or
    /// Jacobian), which the border reads instead of evaluating the link again, and a
    /// stuck link's multiplier its capacity from ([`Profile::stuck_capacity`]).
    cache: RefCell<Vec<Option<IntervalLinearization>>>,
    /// Each link's capstan rows of the order-6 scheme from its last [`super::order6::interval_order6`]
    /// (empty before one), for the error estimate.
    pub(crate) order6: RefCell<Vec<Vec<f64>>>,
    /// The last link's evaluation at its end node, which the next link's start takes
    /// instead of evaluating the same point again.
    end: RefCell<Option<KeptEnd>>,
    /// Each node's rates and turning rates from the last link that evaluated it, which the
    /// order-6 stages at the same node take instead of evaluating it again.
    nodes: RefCell<Vec<NodeRates>>,
    /// Linearizations done with ([`Profile::give`]), refilled by the next points so that
    /// evaluating eq. 13 with friction allocates nothing after the first links.
    // Boxed so that taking and giving one moves a pointer, not its 700 bytes (measured:
    // the moves' memcpy cost S's friction solve 0.18 M instructions).
    #[allow(clippy::vec_box)]
    pub(super) spare: RefCell<Vec<Box<FrictionLinearization>>>,
    /// Links' evaluations the cache no longer holds and the links' scratch buffers, for the
    /// next links to refill.
    spare_links: RefCell<Vec<IntervalLinearization>>,
    #[allow(clippy::vec_box)]
    scratch_links: RefCell<Vec<Box<LinkScratch>>>,
    /// While set ([`Profile::keep_responses`]: the rod's density over its modulus, and its
    /// length), the links' evaluations with derivatives keep eq. 13 with friction's response
    /// to the inertia loads at their start nodes and midpoints ([`Profile::keep_response`]),
    /// for the mass of the linearized dynamics at the same state.
    pub(super) responding: Cell<Option<(f64, f64)>>,
    /// Those responses: link k's start node at 2k, its midpoint at 2k + 1.
    responses: RefCell<Responses>,
    /// Per slip and link, the per-point multipliers' shares and capacity
    /// ([`IntervalLinearization::pointwise`]) a stuck link takes before its first evaluation
    /// on this profile: a verdict's profile holds those of the answer it assesses
    /// ([`Profile::shares`]; docs/stability.md, "Load-history steps"), and so does the
    /// material term's held solve (docs/friction.md section 8, "est25"); empty elsewhere.
    pub(crate) held_shares: Vec<Vec<Option<[f64; 4]>>>,
}

/// Eq. 13 with friction's responses to the unit inertia loads at points (their rates,
/// turning rates and [`FrictionLinearization::load_response`]) and everything they were
/// evaluated from: a point with the same inputs, bit for bit, has the same response. Point
/// i's log tensions, multipliers, turning rates and turning responses are entries
/// `i * count..(i + 1) * count` of the flat buffers (`count` slips), sized once per mesh.
#[derive(Debug, Default)]
struct Responses {
    points: Vec<Response>,
    z: Vec<f64>,
    w: Vec<f64>,
    turning: Vec<f64>,
    turns: Vec<SMatrix<f64, 1, 6>>,
    /// How many times a kept response was returned (tests count the reuse).
    #[cfg(test)]
    hits: std::cell::Cell<usize>,
}

/// One point of [`Responses`].
#[derive(Clone, Debug, Default)]
struct Response {
    /// Whether it holds a response (false before the first, or where eq. 13 was singular).
    valid: bool,
    segment_end: f64,
    state: (Matrix3<f64>, Vector3<f64>, Vector3<f64>),
    /// Whether it was evaluated with multipliers (in the flat buffer `w`).
    multipliers: bool,
    rates: Vector6<f64>,
    /// The response to the six unit loads, one per row.
    loads: SMatrix<f64, 6, 6>,
}

/// The buffers of one link's evaluation ([`super::interval::interval`], and its order-6
/// rows): the log tensions at its nodes and midpoint, which slips load it, their stuck
/// tensions in a history, and the rows of the Jacobian's chain rule in z_m and kappa~_m.
/// The profile keeps them, so that evaluating a link allocates nothing after the first.
#[derive(Debug, Default)]
pub(super) struct LinkScratch {
    pub(super) za: Vec<f64>,
    pub(super) zb: Vec<f64>,
    pub(super) zm: Vec<f64>,
    pub(super) on: Vec<bool>,
    pub(super) stuck: Vec<Option<Stuck>>,
    pub(super) dzm: Vec<SMatrix<f64, 1, 18>>,
    pub(super) dturn_m: Vec<SMatrix<f64, 1, 18>>,
    pub(super) dzm_l: Vec<f64>,
    /// The order-6 rows' log tensions at the quarter stages and their five stages'
    /// turning rates ([`super::order6::interval_order6`]; its midpoint's in `zm`).
    pub(super) z_q: Vec<f64>,
    pub(super) z_tq: Vec<f64>,
    pub(super) turnings: [Vec<f64>; 5],
}

/// Eq. 13 with friction at a node (its rates and turning rates) and everything it was
/// evaluated from, as [`KeptEnd`]; `state` None before the first evaluation.
#[derive(Debug, Default)]
struct NodeRates {
    state: Option<State>,
    segment_end: f64,
    z: Vec<f64>,
    w: Option<Vec<f64>>,
    rates: nalgebra::Vector6<f64>,
    turning: Vec<f64>,
}

/// Eq. 13 with friction at a link's end node and everything it was evaluated from: a
/// link whose start has the same inputs, bit for bit, has the same evaluation (`lin`, None
/// once a link has taken it).
#[derive(Debug)]
struct KeptEnd {
    node: usize,
    segment_end: f64,
    state: State,
    z: Vec<f64>,
    w: Option<Vec<f64>>,
    derivatives: bool,
    lin: Option<Box<FrictionLinearization>>,
}

impl<'a> Profile<'a> {
    /// The profile of `model`'s tendons with friction on `mesh`, constant (z = 0).
    pub(crate) fn new(model: &Model<'a>, mesh: &Mesh) -> Self {
        let robot = model.robot;
        let slipping = friction::slipping(robot);
        let base = slipping.iter().map(|&i| model.tensions[i]).collect();
        let spans = slipping
            .iter()
            .map(|&i| {
                let end = robot.tendons[i].end(robot.length());
                mesh.nodes
                    .iter()
                    .position(|n| n.s >= end)
                    .unwrap_or(mesh.nodes.len() - 1)
            })
            .collect();
        Profile {
            z: vec![vec![0.0; mesh.nodes.len()]; slipping.len()],
            grips: None,
            slipping,
            base,
            spans,
            scratch: RefCell::new(model.clone()),
            quad: RefCell::new(Vec::new()),
            cache: RefCell::new((1..mesh.nodes.len()).map(|_| None).collect()),
            order6: RefCell::new(vec![Vec::new(); mesh.nodes.len() - 1]),
            end: RefCell::new(None),
            nodes: RefCell::new((0..mesh.nodes.len()).map(|_| NodeRates::default()).collect()),
            spare: RefCell::new(Vec::new()),
            spare_links: RefCell::new(Vec::new()),
            scratch_links: RefCell::new(Vec::new()),
            responding: Cell::new(None),
            responses: RefCell::new(Responses::default()),
            held_shares: Vec::new(),
        }
    }

    /// A copy with the same log tensions and a fresh scratch model and cache (tests).
    #[cfg(test)]
    pub(super) fn clone_z(&self) -> Self {
        Profile {
            slipping: self.slipping.clone(),
            base: self.base.clone(),
            spans: self.spans.clone(),
            z: self.z.clone(),
            grips: self.grips.clone(),
            scratch: RefCell::new(self.scratch.borrow().clone()),
            quad: RefCell::new(Vec::new()),
            cache: RefCell::new(self.cache.borrow().iter().map(|_| None).collect()),
            order6: RefCell::new(vec![Vec::new(); self.z[0].len() - 1]),
            end: RefCell::new(None),
            nodes: RefCell::new((0..self.z[0].len()).map(|_| NodeRates::default()).collect()),
            spare: RefCell::new(Vec::new()),
            spare_links: RefCell::new(Vec::new()),
            scratch_links: RefCell::new(Vec::new()),
            responding: Cell::new(None),
            responses: RefCell::new(Responses::default()),
            held_shares: self.held_shares.clone(),
        }
    }

    /// The friction coefficient mu_j of slip j.
    pub(crate) fn coefficient(&self, j: usize) -> f64 {
        self.robot().tendons[self.slipping[j]]
            .active_friction()
            .map_or(0.0, |f| f.coefficient)
    }

    /// Number of tendons with friction.
    pub(crate) fn count(&self) -> usize {
        self.slipping.len()
    }

    /// The tension (N) of slip j where its log tension is `z`.
    pub(crate) fn tension(&self, j: usize, z: f64) -> f64 {
        self.base[j] * z.exp()
    }

    /// Whether slip j loads link k (its span reaches node k + 1).
    pub(crate) fn on_link(&self, j: usize, k: usize) -> bool {
        k < self.spans[j]
    }

    /// Sets `model`'s tension of each tendon with friction to the one it delivers at its
    /// termination, which the jump and tip conditions use.
    pub(crate) fn deliver(&self, model: &mut Model) {
        for (j, &i) in self.slipping.iter().enumerate() {
            model.tensions[i] = self.tension(j, self.z[j][self.spans[j]]);
        }
    }

    /// Every tendon's tension (N) at every node: the profile for the slips, the model's
    /// tension for the others.
    pub(crate) fn node_tensions(&self, model: &Model) -> Vec<Vec<f64>> {
        (0..self.z.first().map_or(0, Vec::len))
            .map(|n| {
                let mut t = model.tensions.clone();
                for (j, &i) in self.slipping.iter().enumerate() {
                    t[i] = self.tension(j, self.z[j][n.min(self.spans[j])]);
                }
                t
            })
            .collect()
    }

    /// Keeps link k's evaluation `lin` for the border (the one it replaces goes to the
    /// spare evaluations, [`Profile::take_link`]).
    pub(crate) fn keep(&self, k: usize, lin: IntervalLinearization) {
        let old = self.cache.borrow_mut()[k].replace(lin);
        if let Some(old) = old {
            self.spare_links.borrow_mut().push(old);
        }
    }

    /// A link evaluation to refill: a spare one, else a new empty one.
    pub(super) fn take_link(&self) -> IntervalLinearization {
        self.spare_links
            .borrow_mut()
            .pop()
            .unwrap_or_else(IntervalLinearization::empty)
    }

    /// Takes back a link evaluation its caller is done with, for the next link to refill.
    pub(super) fn give_link(&self, lin: IntervalLinearization) {
        self.spare_links.borrow_mut().push(lin);
    }

    /// A link's scratch buffers: spare ones, else new ones ([`Profile::give_scratch`]).
    pub(super) fn take_scratch(&self) -> Box<LinkScratch> {
        self.scratch_links.borrow_mut().pop().unwrap_or_default()
    }

    /// Takes back a link's scratch buffers.
    pub(super) fn give_scratch(&self, scratch: Box<LinkScratch>) {
        self.scratch_links.borrow_mut().push(scratch);
    }

    /// Runs `f` on link k's last evaluation (None when it has none).
    pub(crate) fn cached<R>(&self, k: usize, f: impl FnOnce(Option<&IntervalLinearization>) -> R) -> R {
        f(self.cache.borrow()[k].as_ref())
    }

    /// The friction multipliers w_j of the slips on link k in a history (None in full
    /// slip: the motions' signs): -1 or +1 where a slip slides; where it sticks,
    /// w = (z_b - z_a) / C with C from [`Profile::stuck_capacity`], so that the tangential
    /// load follows the log tensions the stick rows set (only C, which the shape changes
    /// slowly, lags: one evaluation of the link behind).
    pub(crate) fn multipliers(&self, k: usize) -> Option<Vec<f64>> {
        self.grips
            .as_ref()
            .map(|g| g.iter().enumerate().map(|(j, g)| self.multiplier(g, j, k)).collect())
    }

    /// Slip j's entry of [`Profile::multipliers`] on link k, `grip` its grip.
    pub(crate) fn multiplier(&self, grip: &Grip, j: usize, k: usize) -> f64 {
        match grip.contacts.get(k) {
            Some(Contact::Stick) => {
                stuck_multiplier(self.z[j][k], self.z[j][k + 1], self.stuck_scale(j, k).unwrap_or(0.0))
            }
            _ => grip.multipliers.get(k).copied().unwrap_or(1.0),
        }
    }

    /// The capacity C that slip j's multiplier on stuck link k divides by: the link's own
    /// from its last evaluation when the profile keeps one (whatever state that was: an
    /// accepted iterate, a rejected trial point or another residual's; so a stuck link's
    /// rows depend on the evaluation before by a term of first order in the change of
    /// state between the two, which vanishes as Newton converges), else the last march's
    /// (None outside a history). With the march's C held over a whole
    /// Newton solve, each pass of march and Newton only moved C by the shape's change over
    /// the pass before (about 1e3 times less per pass): three or four passes per solve of
    /// a stuck step. With the last evaluation's, Newton's own iterations carry C along and
    /// the step settles on the second pass, at the same fixed point (docs/friction.md
    /// section 8, "Where a stuck step's levels spend").
    pub(crate) fn stuck_capacity(&self, j: usize, k: usize) -> Option<f64> {
        let kept = self.cache.borrow()[k]
            .as_ref()
            .and_then(|lin| lin.capacity.get(j).copied())
            .filter(|c| *c > 0.0);
        kept.or_else(|| self.grips.as_ref().and_then(|g| g[j].capacities.get(k).copied()))
    }

    /// The capacity slip j's multiplier W on stuck link k divides by: C_sigma of its
    /// per-point multipliers from the link's last evaluation where it has them
    /// ([`IntervalLinearization::pointwise`]), else [`Profile::stuck_capacity`].
    pub(crate) fn stuck_scale(&self, j: usize, k: usize) -> Option<f64> {
        self.pointwise(j, k).map(|p| p[3]).or_else(|| self.stuck_capacity(j, k))
    }

    /// Slip j's per-point multipliers' shares and capacity on link k from the link's last
    /// evaluation, where it sticks there with them (before one, the `held_shares`).
    fn pointwise(&self, j: usize, k: usize) -> Option<[f64; 4]> {
        if !self.sticks(j, k) {
            return None;
        }
        self.cache.borrow()[k]
            .as_ref()
            .and_then(|lin| lin.pointwise.get(j).copied().flatten())
            .or_else(|| self.held_shares.get(j).and_then(|s| s.get(k).copied().flatten()))
    }

    /// Each slip's per-point multipliers' shares and capacity on every link (None where it
    /// does not stick with them), as the next evaluation of each link would take them: what
    /// a profile of the same answer holds as its `held_shares`.
    pub(crate) fn shares(&self) -> Vec<Vec<Option<[f64; 4]>>> {
        let links = self.cache.borrow().len();
        (0..self.count())
            .map(|j| (0..links).map(|k| self.pointwise(j, k)).collect())
            .collect()
    }

    /// The shares (sigma_a, sigma_m, sigma_b) of slip j's multiplier at link k's start,
    /// midpoint and end, where it sticks there with per-point multipliers.
    pub(crate) fn sigma(&self, j: usize, k: usize) -> Option<[f64; 3]> {
        self.pointwise(j, k).map(|p| [p[0], p[1], p[2]])
    }

    /// The multipliers at link k's start, midpoint and end from the link's `w`
    /// ([`Profile::multipliers`]): W sigma_P for a slip stuck there with per-point
    /// multipliers, w elsewhere (docs/friction.md section 8, "ord23").
    pub(crate) fn point_multipliers(&self, k: usize, w: &[f64]) -> [Vec<f64>; 3] {
        let mut out = [w.to_vec(), w.to_vec(), w.to_vec()];
        for (j, &w) in w.iter().enumerate() {
            for (points, at) in out.iter_mut().zip(self.point_multiplier(j, k, w)) {
                points[j] = at;
            }
        }
        out
    }

    /// Slip j's entries of [`Profile::point_multipliers`] on link k from its multiplier `w`.
    pub(crate) fn point_multiplier(&self, j: usize, k: usize, w: f64) -> [f64; 3] {
        match self.sigma(j, k) {
            Some(sigma) => sigma.map(|sigma| w * sigma),
            None => [w; 3],
        }
    }

    /// Whether slip j sticks on link k (a history's stick row replaces its capstan row).
    pub(crate) fn sticks(&self, j: usize, k: usize) -> bool {
        self.grips
            .as_ref()
            .is_some_and(|g| g[j].contacts.get(k) == Some(&Contact::Stick))
    }

    /// Eq. 13 with friction at a site and state, the slips at log tensions `z` and
    /// multipliers `w` (the motions' signs when None), with its derivatives when
    /// `derivatives`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn point(
        &self,
        site: &Site,
        segment_end: f64,
        R: &nalgebra::Matrix3<f64>,
        y: (&Vector3<f64>, &Vector3<f64>),
        z: &[f64],
        w: Option<&[f64]>,
        derivatives: bool,
    ) -> Result<Box<FrictionLinearization>> {
        let mut model = self.scratch.borrow_mut();
        for (j, &i) in self.slipping.iter().enumerate() {
            model.tensions[i] = self.tension(j, z[j]);
        }
        let mut lin = self.spare.borrow_mut().pop().unwrap_or_default();
        friction::linearize_into(
            &model,
            site,
            segment_end,
            (R, y.0, y.1),
            &self.slipping,
            w,
            derivatives,
            &mut lin,
        )?;
        Ok(lin)
    }

    /// Takes back a linearization of [`Profile::point`] that its caller is done with, for
    /// the next point to refill.
    pub(super) fn give(&self, lin: Box<FrictionLinearization>) {
        self.spare.borrow_mut().push(lin);
    }

    /// [`Profile::point`] at node k (state `a`, log tensions `z`, multipliers `w`), taken
    /// from the last link's end when that was evaluated from the same inputs (with
    /// derivatives if these need them).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn start_point(
        &self,
        k: usize,
        site: &Site,
        segment_end: f64,
        a: &State,
        z: &[f64],
        w: Option<&[f64]>,
        derivatives: bool,
    ) -> Result<Box<FrictionLinearization>> {
        let taken = self.end.borrow_mut().as_mut().and_then(|kept| {
            let lin = kept.lin.take()?;
            let same = kept.node == k
                && kept.segment_end == segment_end
                && kept.state == *a
                && kept.z == z
                && kept.w.as_deref() == w
                && (kept.derivatives || !derivatives);
            Some((same, lin))
        });
        match taken {
            Some((true, lin)) => return Ok(lin),
            Some((false, lin)) => self.give(lin),
            None => {}
        }
        self.point(site, segment_end, &a.R, (&a.v, &a.u), z, w, derivatives)
    }

    /// Keeps the evaluation `lin` at node n (state `b`, log tensions `z`) for the link that
    /// starts there ([`Profile::start_point`]), in the buffers of the last one kept.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn keep_point(
        &self,
        n: usize,
        segment_end: f64,
        b: &State,
        z: &[f64],
        w: Option<&[f64]>,
        derivatives: bool,
        lin: Box<FrictionLinearization>,
    ) {
        let mut end = self.end.borrow_mut();
        let kept = end.get_or_insert_with(|| KeptEnd {
            node: 0,
            segment_end,
            state: *b,
            z: Vec::new(),
            w: None,
            derivatives,
            lin: None,
        });
        kept.node = n;
        kept.segment_end = segment_end;
        kept.state = *b;
        kept.z.clear();
        kept.z.extend_from_slice(z);
        copy_multipliers(&mut kept.w, w);
        kept.derivatives = derivatives;
        let old = kept.lin.replace(lin);
        drop(end);
        if let Some(old) = old {
            self.give(old);
        }
    }

    /// Keeps the rates and turning rates of `lin`, eq. 13 with friction at node n (state
    /// `state`, log tensions `z`, multipliers `w`, segment end `segment_end`).
    pub(super) fn keep_node(
        &self,
        n: usize,
        segment_end: f64,
        state: &State,
        (z, w): (&[f64], Option<&[f64]>),
        lin: &FrictionLinearization,
    ) {
        let mut nodes = self.nodes.borrow_mut();
        let Some(kept) = nodes.get_mut(n) else {
            return;
        };
        kept.state = Some(*state);
        kept.segment_end = segment_end;
        kept.z.clear();
        kept.z.extend_from_slice(z);
        copy_multipliers(&mut kept.w, w);
        kept.rates = lin.lin.rates;
        kept.turning.clear();
        kept.turning.extend_from_slice(&lin.turning);
    }

    /// The rates (v', u') and turning rates of eq. 13 with friction at node n kept by
    /// [`Profile::keep_node`] when it was evaluated from the same inputs, bit for bit (the
    /// values an evaluation would give again), into `turning`; None otherwise.
    pub(super) fn node_rates(
        &self,
        n: usize,
        segment_end: f64,
        state: &State,
        (z, w): (&[f64], Option<&[f64]>),
        turning: &mut Vec<f64>,
    ) -> Option<nalgebra::Vector6<f64>> {
        let nodes = self.nodes.borrow();
        let kept = nodes.get(n)?;
        let same = kept.state.as_ref() == Some(state)
            && kept.segment_end == segment_end
            && kept.z == z
            && kept.w.as_deref() == w;
        if !same {
            return None;
        }
        turning.clone_from(&kept.turning);
        Some(kept.rates)
    }

    /// The robot.
    pub(crate) fn robot(&self) -> &'a crate::Robot {
        self.scratch.borrow().robot
    }
}

/// `w` copied into `kept`, reusing its buffer where both are there.
fn copy_multipliers(kept: &mut Option<Vec<f64>>, w: Option<&[f64]>) {
    match (kept, w) {
        (Some(old), Some(w)) => {
            old.clear();
            old.extend_from_slice(w);
        }
        (old, w) => *old = w.map(<[f64]>::to_vec),
    }
}
