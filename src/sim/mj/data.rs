//! The owning `Data` type: the simulation state (`mjData`) of one model.

use super::{MjError, Model, ObjType};
use mujoco_sys as sys;
use std::ptr::NonNull;
use std::sync::Arc;

/// MuJoCo's warning counters (`mjtWarning`) that this crate reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Warning {
    /// (Near) singular inertia matrix.
    Inertia,
    /// Too many contacts.
    ContactFull,
    /// Too many constraints.
    ConstraintFull,
    /// Bad number in qpos.
    BadQpos,
    /// Bad number in qvel.
    BadQvel,
    /// Bad number in qacc: MuJoCo reset the state (numerical instability).
    BadQacc,
}

impl Warning {
    fn index(self) -> usize {
        let w = match self {
            Warning::Inertia => sys::mjtWarning::mjWARN_INERTIA,
            Warning::ContactFull => sys::mjtWarning::mjWARN_CONTACTFULL,
            Warning::ConstraintFull => sys::mjtWarning::mjWARN_CNSTRFULL,
            Warning::BadQpos => sys::mjtWarning::mjWARN_BADQPOS,
            Warning::BadQvel => sys::mjtWarning::mjWARN_BADQVEL,
            Warning::BadQacc => sys::mjtWarning::mjWARN_BADQACC,
        };
        w as usize
    }
}

/// One contact from MuJoCo's contact list (a read-only view of `mjContact`).
#[repr(transparent)]
pub struct Contact(sys::mjContact);

impl Contact {
    /// First geom of the pair.
    pub fn geom1(&self) -> usize {
        super::engine::contact_geoms(&self.0)[0] as usize
    }
    /// Second geom of the pair.
    pub fn geom2(&self) -> usize {
        super::engine::contact_geoms(&self.0)[1] as usize
    }
    /// Signed distance (negative: penetration).
    pub fn dist(&self) -> f64 {
        self.0.dist
    }
    /// Contact point in world coordinates.
    pub fn pos(&self) -> [f64; 3] {
        self.0.pos
    }
}

/// Simulation state of one [`Model`]; holds the model alive. Freed with
/// `mj_deleteData` on drop.
pub struct Data {
    ptr: NonNull<sys::mjData>,
    model: Arc<Model>,
}

// SAFETY: an mjData has no thread affinity; all mutation goes through
// `&mut self`, and the shared model is Sync.
unsafe impl Send for Data {}

impl Data {
    /// Allocates a state for `model`, at the model's reference configuration.
    ///
    /// # Errors
    /// [`MjError::Alloc`] if MuJoCo cannot allocate it.
    pub fn new(model: Arc<Model>) -> Result<Self, MjError> {
        let mut raw = std::ptr::null_mut();
        // SAFETY: the model is live for as long as `model` (kept in Self);
        // bp_make_data writes the new mjData (or null) into `raw`.
        super::guarded(unsafe { sys::bp_make_data(model.as_ptr(), &mut raw) })?;
        let ptr = NonNull::new(raw).ok_or(MjError::Alloc)?;
        Ok(Self { ptr, model })
    }

    /// The model this state belongs to.
    pub fn model(&self) -> &Arc<Model> {
        &self.model
    }

    /// The model, to change its parameters, where this state is the only holder of it (a
    /// [`Model::try_clone`] given to this state alone).
    ///
    /// # Errors
    /// [`MjError::ModelShared`] where another holds it too.
    pub fn model_mut(&mut self) -> Result<&mut Model, MjError> {
        Arc::get_mut(&mut self.model).ok_or(MjError::ModelShared)
    }

    fn m(&self) -> *const sys::mjModel {
        self.model.as_ptr()
    }

    fn raw(&self) -> &sys::mjData {
        // SAFETY: `ptr` is a live mjData owned by self.
        unsafe { self.ptr.as_ref() }
    }

    /// The raw `mjData` (for the renderer).
    #[cfg(feature = "render")]
    pub(crate) fn as_mut_ptr(&mut self) -> *mut sys::mjData {
        self.ptr.as_ptr()
    }

    /// One physics step (`mj_step`).
    ///
    /// # Errors
    /// [`MjError::Fatal`] when MuJoCo stops on an error; the state is then
    /// unusable until [`Data::reset`] or [`Data::copy_from`].
    pub fn step(&mut self) -> Result<(), MjError> {
        // SAFETY: model and data are live and belong together (same Arc).
        super::guarded(unsafe { sys::bp_step(self.m(), self.ptr.as_ptr()) })
    }

    /// Recomputes every derived quantity from the state (`mj_forward`).
    ///
    /// # Errors
    /// As [`Data::step`].
    pub fn forward(&mut self) -> Result<(), MjError> {
        // SAFETY: as in `step`.
        super::guarded(unsafe { sys::bp_forward(self.m(), self.ptr.as_ptr()) })
    }

    /// Position-dependent quantities only: forward kinematics, centres of
    /// mass, and velocities of the bodies (`mj_kinematics`, `mj_comPos`,
    /// `mj_comVel`), followed by collision detection (`mj_collision`) when
    /// `contacts` is set. Positions, orientations, `mj_objectVelocity` and
    /// (with `contacts`) the contact list are then up to date; forces and
    /// accelerations are not.
    ///
    /// # Errors
    /// As [`Data::step`].
    pub fn kinematics(&mut self, contacts: bool) -> Result<(), MjError> {
        let (m, d) = (self.m(), self.ptr.as_ptr());
        // SAFETY: as in `step`; bp_kinematics calls the first stages of
        // mj_forward in the order mj_forward calls them.
        super::guarded(unsafe { sys::bp_kinematics(m, d, i32::from(contacts)) })
    }

    /// Resets to the model's reference configuration (`mj_resetData`).
    ///
    /// # Errors
    /// As [`Data::step`].
    pub fn reset(&mut self) -> Result<(), MjError> {
        // SAFETY: as in `step`.
        super::guarded(unsafe { sys::bp_reset_data(self.m(), self.ptr.as_ptr()) })
    }

    /// Copies the whole state of `src` (warm-start and warning counters
    /// included) into `self` (`mj_copyData`).
    ///
    /// # Errors
    /// [`MjError::ModelMismatch`] if the two states belong to different models.
    pub fn copy_from(&mut self, src: &Data) -> Result<(), MjError> {
        if !self.model.same_lineage(&src.model) {
            return Err(MjError::ModelMismatch);
        }
        // SAFETY: both states were made for this model or a copy of the same load, whose sizes
        // are the same (nothing changes a model's sizes), so their buffers have the same sizes;
        // `self` is exclusively borrowed.
        super::guarded(unsafe { sys::bp_copy_data(self.ptr.as_ptr(), self.m(), src.ptr.as_ptr()) })
    }

    /// A deep copy of this state.
    ///
    /// # Errors
    /// [`MjError::Alloc`] if MuJoCo cannot allocate it.
    pub fn try_clone(&self) -> Result<Data, MjError> {
        let mut d = Data::new(self.model.clone())?;
        d.copy_from(self)?;
        Ok(d)
    }

    /// Simulation time in seconds.
    pub fn time(&self) -> f64 {
        self.raw().time
    }

    /// Generalised positions (`nq`).
    pub fn qpos(&self) -> &[f64] {
        self.reals(self.raw().qpos, self.model.nq())
    }
    /// Mutable generalised positions.
    pub fn qpos_mut(&mut self) -> &mut [f64] {
        let (p, n) = (self.raw().qpos, self.model.nq());
        self.reals_mut(p, n)
    }
    /// Generalised velocities (`nv`).
    pub fn qvel(&self) -> &[f64] {
        self.reals(self.raw().qvel, self.model.nv())
    }
    /// Mutable generalised velocities.
    pub fn qvel_mut(&mut self) -> &mut [f64] {
        let (p, n) = (self.raw().qvel, self.model.nv());
        self.reals_mut(p, n)
    }
    /// Actuator controls (`nu`).
    pub fn ctrl(&self) -> &[f64] {
        self.reals(self.raw().ctrl, self.model.nu())
    }
    /// Mutable actuator controls.
    pub fn ctrl_mut(&mut self) -> &mut [f64] {
        let (p, n) = (self.raw().ctrl, self.model.nu());
        self.reals_mut(p, n)
    }
    /// Generalised accelerations (`nv`).
    pub fn qacc(&self) -> &[f64] {
        self.reals(self.raw().qacc, self.model.nv())
    }
    /// Warm-start accelerations of the constraint solver (`nv`).
    pub fn qacc_warmstart(&self) -> &[f64] {
        self.reals(self.raw().qacc_warmstart, self.model.nv())
    }
    /// Warm-start accelerations, writable (zero after `mj_resetData`).
    pub fn qacc_warmstart_mut(&mut self) -> &mut [f64] {
        let (p, n) = (self.raw().qacc_warmstart, self.model.nv());
        self.reals_mut(p, n)
    }

    /// Mocap body positions.
    pub fn mocap_pos(&self) -> &[[f64; 3]] {
        self.vecs(self.raw().mocap_pos, self.model.nmocap())
    }
    /// Mutable mocap body positions.
    pub fn mocap_pos_mut(&mut self) -> &mut [[f64; 3]] {
        let (p, n) = (self.raw().mocap_pos, self.model.nmocap());
        self.vecs_mut(p, n)
    }
    /// Mocap body orientations (w, x, y, z).
    pub fn mocap_quat(&self) -> &[[f64; 4]] {
        self.vecs(self.raw().mocap_quat, self.model.nmocap())
    }
    /// Mutable mocap body orientations.
    pub fn mocap_quat_mut(&mut self) -> &mut [[f64; 4]] {
        let (p, n) = (self.raw().mocap_quat, self.model.nmocap());
        self.vecs_mut(p, n)
    }

    /// Body frame positions in world coordinates (`xpos`).
    pub fn xpos(&self) -> &[[f64; 3]] {
        self.vecs(self.raw().xpos, self.model.nbody())
    }
    /// Body frame orientations (`xquat`).
    pub fn xquat(&self) -> &[[f64; 4]] {
        self.vecs(self.raw().xquat, self.model.nbody())
    }
    /// Geom positions in world coordinates (`geom_xpos`).
    pub fn geom_xpos(&self) -> &[[f64; 3]] {
        self.vecs(self.raw().geom_xpos, self.model.ngeom())
    }
    /// Geom orientations as row-major 3×3 matrices (`geom_xmat`).
    pub fn geom_xmat(&self) -> &[[f64; 9]] {
        self.vecs(self.raw().geom_xmat, self.model.ngeom())
    }
    /// Site positions in world coordinates (`site_xpos`).
    pub fn site_xpos(&self) -> &[[f64; 3]] {
        self.vecs(self.raw().site_xpos, self.model.nsite())
    }
    /// Site orientations as row-major 3×3 matrices (`site_xmat`).
    pub fn site_xmat(&self) -> &[[f64; 9]] {
        self.vecs(self.raw().site_xmat, self.model.nsite())
    }

    /// The contacts MuJoCo found at the last collision detection.
    pub fn contacts(&self) -> &[Contact] {
        let n = self.raw().ncon.max(0) as usize;
        if n == 0 {
            return &[];
        }
        // SAFETY: `contact` holds at least `ncon` initialised mjContact
        // entries; Contact is a transparent wrapper of mjContact.
        unsafe { std::slice::from_raw_parts(self.raw().contact as *const Contact, n) }
    }

    /// How many times MuJoCo raised `warning` since the last reset.
    pub fn warning_count(&self, warning: Warning) -> i32 {
        self.raw().warning[warning.index()].number
    }

    /// 6-D velocity `[angular; linear]` of an object (`mj_objectVelocity`),
    /// in world coordinates, or in the object's frame when `local`.
    ///
    /// # Errors
    /// [`MjError::OutOfRange`] if `id` is not an object of `kind`.
    pub fn object_velocity(&self, kind: ObjType, id: usize, local: bool) -> Result<[f64; 6], MjError> {
        let count = match kind {
            ObjType::Body | ObjType::XBody => self.model.nbody(),
            ObjType::Geom => self.model.ngeom(),
            ObjType::Site => self.model.nsite(),
            _ => 0,
        };
        if id >= count {
            return Err(MjError::OutOfRange { kind: kind.label(), index: id, count });
        }
        let mut res = [0.0; 6];
        // SAFETY: model/data are live and matched; `id` is in range for
        // `kind` (checked above); `res` has the 6 slots MuJoCo writes.
        unsafe {
            sys::mj_objectVelocity(self.m(), self.ptr.as_ptr(), kind.raw(), id as i32, res.as_mut_ptr(), local as i32)
        };
        Ok(res)
    }

    fn reals(&self, p: *const f64, n: usize) -> &[f64] {
        if n == 0 || p.is_null() {
            return &[];
        }
        // SAFETY: callers pass an mjData array with the model count MuJoCo
        // sized it with; it lives as long as `self`.
        unsafe { std::slice::from_raw_parts(p, n) }
    }

    fn reals_mut(&mut self, p: *mut f64, n: usize) -> &mut [f64] {
        if n == 0 || p.is_null() {
            return &mut [];
        }
        // SAFETY: as in `reals`; `&mut self` makes the access exclusive.
        unsafe { std::slice::from_raw_parts_mut(p, n) }
    }

    fn vecs<const K: usize>(&self, p: *const f64, n: usize) -> &[[f64; K]] {
        if n == 0 || p.is_null() {
            return &[];
        }
        // SAFETY: callers pass an mjData array of n*K contiguous reals;
        // [f64; K] has the layout of K consecutive f64.
        unsafe { std::slice::from_raw_parts(p as *const [f64; K], n) }
    }

    fn vecs_mut<const K: usize>(&mut self, p: *mut f64, n: usize) -> &mut [[f64; K]] {
        if n == 0 || p.is_null() {
            return &mut [];
        }
        // SAFETY: as in `vecs`; `&mut self` makes the access exclusive.
        unsafe { std::slice::from_raw_parts_mut(p as *mut [f64; K], n) }
    }
}

impl Drop for Data {
    fn drop(&mut self) {
        // SAFETY: `ptr` came from mj_makeData and is freed exactly once.
        unsafe { sys::mj_deleteData(self.ptr.as_ptr()) };
    }
}
