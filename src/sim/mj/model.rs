//! The owning `Model` type: a compiled MuJoCo model (`mjModel`).

use super::{MjError, ObjType, Vfs};
use mujoco_sys as sys;
use std::ffi::{CStr, CString};
use std::path::Path;
use std::ptr::NonNull;

/// Number of reals MuJoCo keeps per equality constraint (`mjNEQDATA`).
pub const NEQDATA: usize = sys::mjNEQDATA as usize;

/// A compiled MuJoCo model. Freed with `mj_deleteModel` on drop.
pub struct Model {
    ptr: NonNull<sys::mjModel>,
    /// Which load this model is, or is a copy of ([`Model::try_clone`]): models of one lineage
    /// have the same sizes (nothing here changes a size), so their states' buffers match.
    lineage: u64,
}

/// The next model load's lineage.
static LINEAGE: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

// SAFETY: an mjModel is a self-contained heap block; MuJoCo only reads it
// during simulation, and every mutation here goes through `&mut self`, so
// sharing `&Model` across threads and moving it between threads is sound.
unsafe impl Send for Model {}
// SAFETY: see `Send`: shared references only read.
unsafe impl Sync for Model {}

const ERROR_BUF: usize = 1000;

impl Model {
    /// Loads an MJCF file from disk; includes and mesh files resolve relative
    /// to the folder of `path`.
    ///
    /// # Errors
    /// [`MjError::MissingFile`] if the file is absent, [`MjError::Load`] with
    /// MuJoCo's message if it fails to parse or compile.
    pub fn from_xml_file(path: &Path) -> Result<Self, MjError> {
        if !path.exists() {
            return Err(MjError::MissingFile { path: path.to_owned() });
        }
        Self::load(path, None)
    }

    /// Compiles MJCF held in memory. The text is registered in a virtual file
    /// system under `virtual_path` and loaded from there, so `<include>`,
    /// `meshdir` and `texturedir` resolve relative to `virtual_path`'s folder
    /// on disk (MuJoCo 2.2.2 has no working absolute include paths).
    ///
    /// # Errors
    /// [`MjError::Load`] with MuJoCo's message if the XML does not compile,
    /// [`MjError::Vfs`]/[`MjError::InvalidName`] for an unusable `virtual_path`.
    pub fn from_xml_string(xml: &str, virtual_path: &Path) -> Result<Self, MjError> {
        let name = path_str(virtual_path)?;
        let mut vfs = Vfs::new();
        vfs.add(name, xml.as_bytes())?;
        Self::load(virtual_path, Some(&vfs))
    }

    fn load(path: &Path, vfs: Option<&Vfs>) -> Result<Self, MjError> {
        super::engine::check_version()?;
        let c_path = CString::new(path_str(path)?)
            .map_err(|_| MjError::InvalidName { name: path.display().to_string(), reason: "contains a NUL byte" })?;
        let mut err = vec![0 as std::os::raw::c_char; ERROR_BUF];
        let vfs_ptr = vfs.map_or(std::ptr::null(), Vfs::as_ptr);
        let raw = {
            // MuJoCo 2.2.2's compiler swaps the global error handlers while it
            // runs and leaves its own in place when compiling fails: loads are
            // serialised and ours are put back after each one.
            static LOADING: std::sync::Mutex<()> = std::sync::Mutex::new(());
            let _one_at_a_time = LOADING.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
            // SAFETY: `c_path` is NUL-terminated, `vfs_ptr` is null or a live
            // mjVFS, and `err` has exactly ERROR_BUF writable bytes, which is the
            // size we pass; MuJoCo NUL-terminates what it writes.
            let raw = unsafe { sys::mj_loadXML(c_path.as_ptr(), vfs_ptr, err.as_mut_ptr(), ERROR_BUF as i32) };
            super::set_handlers();
            raw
        };
        match NonNull::new(raw) {
            Some(ptr) => Ok(Self { ptr, lineage: LINEAGE.fetch_add(1, std::sync::atomic::Ordering::Relaxed) }),
            None => {
                // SAFETY: `err` is NUL-terminated: it was zeroed and MuJoCo
                // writes at most ERROR_BUF-1 characters plus a NUL.
                let message = unsafe { CStr::from_ptr(err.as_ptr()) }.to_string_lossy().trim().to_owned();
                Err(MjError::Load { path: path.to_owned(), message })
            }
        }
    }

    /// A deep copy (`mj_copyModel`) of the same lineage: a state of either model may be copied
    /// into a state of the other ([`super::Data::copy_from`]). What varies per episode
    /// ([`crate::sim::dynamics`]) is set on a copy that one state owns.
    ///
    /// # Errors
    /// [`MjError::Alloc`] if MuJoCo cannot allocate it.
    pub fn try_clone(&self) -> Result<Self, MjError> {
        let mut raw = std::ptr::null_mut();
        // SAFETY: `self` is a live model; bp_copy_model writes a new model (or null) into `raw`.
        super::guarded(unsafe { sys::bp_copy_model(self.as_ptr(), &mut raw) })?;
        let ptr = NonNull::new(raw).ok_or(MjError::Alloc)?;
        Ok(Self { ptr, lineage: self.lineage })
    }

    /// Whether `other` is this model or a copy of the same load (same sizes).
    pub(crate) fn same_lineage(&self, other: &Model) -> bool {
        self.lineage == other.lineage
    }

    pub(crate) fn as_ptr(&self) -> *const sys::mjModel {
        self.ptr.as_ptr()
    }

    fn raw(&self) -> &sys::mjModel {
        // SAFETY: `ptr` is a live mjModel owned by `self` for its lifetime.
        unsafe { self.ptr.as_ref() }
    }

    fn raw_mut(&mut self) -> &mut sys::mjModel {
        // SAFETY: as in `raw`, and `&mut self` guarantees exclusive access.
        unsafe { self.ptr.as_mut() }
    }

    /// Number of generalised coordinates.
    pub fn nq(&self) -> usize {
        self.raw().nq as usize
    }
    /// Number of degrees of freedom.
    pub fn nv(&self) -> usize {
        self.raw().nv as usize
    }
    /// Number of actuators.
    pub fn nu(&self) -> usize {
        self.raw().nu as usize
    }
    /// Number of bodies (the world body included).
    pub fn nbody(&self) -> usize {
        self.raw().nbody as usize
    }
    /// Number of geoms.
    pub fn ngeom(&self) -> usize {
        self.raw().ngeom as usize
    }
    /// Number of sites.
    pub fn nsite(&self) -> usize {
        self.raw().nsite as usize
    }
    /// Number of joints.
    pub fn njnt(&self) -> usize {
        self.raw().njnt as usize
    }
    /// Number of mocap bodies.
    pub fn nmocap(&self) -> usize {
        self.raw().nmocap as usize
    }
    /// Number of equality constraints.
    pub fn neq(&self) -> usize {
        self.raw().neq as usize
    }
    /// Number of excluded body pairs (`<contact><exclude>`).
    pub fn nexclude(&self) -> usize {
        self.raw().nexclude as usize
    }
    /// Number of materials.
    pub fn nmat(&self) -> usize {
        self.raw().nmat as usize
    }

    /// The simulation timestep in seconds.
    pub fn timestep(&self) -> f64 {
        self.raw().opt.timestep
    }

    /// The id of the object of `kind` called `name`.
    ///
    /// # Errors
    /// [`MjError::UnknownName`] if the model has no such object.
    pub fn id(&self, kind: ObjType, name: &str) -> Result<usize, MjError> {
        let c_name = CString::new(name)
            .map_err(|_| MjError::InvalidName { name: name.to_owned(), reason: "contains a NUL byte" })?;
        // SAFETY: the model is live and `c_name` is NUL-terminated.
        let id = unsafe { sys::mj_name2id(self.as_ptr(), kind.raw(), c_name.as_ptr()) };
        usize::try_from(id).map_err(|_| MjError::UnknownName { kind: kind.label(), name: name.to_owned() })
    }

    /// The name of object `id` of `kind`, or `None` if it is unnamed or out of range.
    pub fn name(&self, kind: ObjType, id: usize) -> Option<String> {
        let id = i32::try_from(id).ok()?;
        // SAFETY: the model is live; mj_id2name checks the id range itself
        // and returns NULL for out-of-range or unnamed objects.
        let p = unsafe { sys::mj_id2name(self.as_ptr(), kind.raw(), id) };
        if p.is_null() {
            return None;
        }
        // SAFETY: a non-null result points into the model's NUL-terminated names buffer.
        Some(unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
    }

    /// Body id of each geom (`geom_bodyid`).
    pub fn geom_bodyid(&self) -> &[i32] {
        self.ints(self.raw().geom_bodyid, self.ngeom())
    }
    /// Parent body of each body (`body_parentid`).
    pub fn body_parentid(&self) -> &[i32] {
        self.ints(self.raw().body_parentid, self.nbody())
    }
    /// Mocap index of each body, -1 for ordinary bodies (`body_mocapid`).
    pub fn body_mocapid(&self) -> &[i32] {
        self.ints(self.raw().body_mocapid, self.nbody())
    }
    /// Address of each joint's first coordinate in qpos (`jnt_qposadr`).
    pub fn jnt_qposadr(&self) -> &[i32] {
        self.ints(self.raw().jnt_qposadr, self.njnt())
    }
    /// The joint (or other transmission target) of each actuator: the first
    /// of `actuator_trnid`'s two ids.
    pub fn actuator_joint(&self) -> Vec<i32> {
        self.ints(self.raw().actuator_trnid, 2 * self.nu()).chunks_exact(2).map(|c| c[0]).collect()
    }
    /// Address of each joint's first degree of freedom in qvel (`jnt_dofadr`).
    pub fn jnt_dofadr(&self) -> &[i32] {
        self.ints(self.raw().jnt_dofadr, self.njnt())
    }
    /// Type of each equality constraint (`eq_type`, an `mjtEq` value).
    pub fn eq_type(&self) -> &[i32] {
        self.ints(self.raw().eq_type, self.neq())
    }
    /// First object of each equality constraint (`eq_obj1id`).
    pub fn eq_obj1id(&self) -> &[i32] {
        self.ints(self.raw().eq_obj1id, self.neq())
    }
    /// Second object of each equality constraint (`eq_obj2id`).
    pub fn eq_obj2id(&self) -> &[i32] {
        self.ints(self.raw().eq_obj2id, self.neq())
    }
    /// Material of each geom, -1 for none (`geom_matid`).
    pub fn geom_matid(&self) -> &[i32] {
        self.ints(self.raw().geom_matid, self.ngeom())
    }

    /// Bounding-sphere radius of each geom (`geom_rbound`).
    pub fn geom_rbound(&self) -> &[f64] {
        // SAFETY: geom_rbound holds ngeom reals owned by the model.
        unsafe { rows::<f64, 1>(self.raw().geom_rbound, self.ngeom()) }.as_flattened()
    }

    /// Contact type bits of each geom (`geom_contype`).
    pub fn geom_contype(&self) -> &[i32] {
        self.ints(self.raw().geom_contype, self.ngeom())
    }
    /// Contact affinity bits of each geom (`geom_conaffinity`).
    pub fn geom_conaffinity(&self) -> &[i32] {
        self.ints(self.raw().geom_conaffinity, self.ngeom())
    }
    /// Weld group of each body (`body_weldid`).
    pub fn body_weldid(&self) -> &[i32] {
        self.ints(self.raw().body_weldid, self.nbody())
    }

    /// Numeric data of each equality constraint (`eq_data`, `mjNEQDATA` reals each).
    pub fn eq_data(&self) -> &[[f64; NEQDATA]] {
        // SAFETY: eq_data holds neq × mjNEQDATA contiguous f64 owned by the model.
        unsafe { rows(self.raw().eq_data, self.neq()) }
    }

    /// Mutable `eq_data`, e.g. to reset a weld's relative pose.
    pub fn eq_data_mut(&mut self) -> &mut [[f64; NEQDATA]] {
        let (p, n) = (self.raw_mut().eq_data, self.neq());
        // SAFETY: as in `eq_data`; `&mut self` gives exclusive access.
        unsafe { rows_mut(p, n) }
    }

    /// Changes the material of geom `geom` (affects rendering only).
    ///
    /// # Errors
    /// [`MjError::OutOfRange`] for a bad geom or material index.
    pub fn set_geom_material(&mut self, geom: usize, material: usize) -> Result<(), MjError> {
        let (ngeom, nmat) = (self.ngeom(), self.nmat());
        if geom >= ngeom {
            return Err(MjError::OutOfRange { kind: "geom", index: geom, count: ngeom });
        }
        if material >= nmat {
            return Err(MjError::OutOfRange { kind: "material", index: material, count: nmat });
        }
        let p = self.raw_mut().geom_matid;
        // SAFETY: geom_matid has ngeom entries and `geom < ngeom` was checked.
        unsafe { *p.add(geom) = material as i32 };
        Ok(())
    }

    /// Size parameters of each geom (`geom_size`: a box's half extents).
    pub fn geom_size(&self) -> &[[f64; 3]] {
        // SAFETY: MuJoCo sizes geom_size as ngeom × 3 reals; the model outlives `&self`.
        unsafe { rows(self.raw().geom_size, self.ngeom()) }
    }

    /// RGBA of each material (`mat_rgba`).
    pub fn mat_rgba(&self) -> &[[f32; 4]] {
        // SAFETY: MuJoCo sizes mat_rgba as nmat × 4 floats; the model outlives `&self`.
        unsafe { rows(self.raw().mat_rgba, self.nmat()) }
    }

    /// Friction of each geom (`geom_friction`: sliding, torsional, rolling).
    pub fn geom_friction(&self) -> &[[f64; 3]] {
        let (p, n) = (self.raw().geom_friction, self.ngeom());
        // SAFETY: MuJoCo sizes geom_friction as ngeom × 3 reals; the model outlives `&self`.
        unsafe { rows(p, n) }
    }
    /// Mutable `geom_friction`.
    pub fn geom_friction_mut(&mut self) -> &mut [[f64; 3]] {
        let (p, n) = (self.raw_mut().geom_friction, self.ngeom());
        // SAFETY: as in `geom_friction`; `&mut self` gives exclusive access.
        unsafe { rows_mut(p, n) }
    }
    /// Contact reference of each geom (`geom_solref`: time constant, damping ratio).
    pub fn geom_solref(&self) -> &[[f64; 2]] {
        let (p, n) = (self.raw().geom_solref, self.ngeom());
        // SAFETY: MuJoCo sizes geom_solref as ngeom × mjNREF (2) reals.
        unsafe { rows(p, n) }
    }
    /// Mutable `geom_solref`.
    pub fn geom_solref_mut(&mut self) -> &mut [[f64; 2]] {
        let (p, n) = (self.raw_mut().geom_solref, self.ngeom());
        // SAFETY: as in `geom_solref`; `&mut self` gives exclusive access.
        unsafe { rows_mut(p, n) }
    }
    /// Contact impedance of each geom (`geom_solimp`: dmin, dmax, width, midpoint, power).
    pub fn geom_solimp(&self) -> &[[f64; 5]] {
        let (p, n) = (self.raw().geom_solimp, self.ngeom());
        // SAFETY: MuJoCo sizes geom_solimp as ngeom × mjNIMP (5) reals.
        unsafe { rows(p, n) }
    }
    /// Mutable `geom_solimp`.
    pub fn geom_solimp_mut(&mut self) -> &mut [[f64; 5]] {
        let (p, n) = (self.raw_mut().geom_solimp, self.ngeom());
        // SAFETY: as in `geom_solimp`; `&mut self` gives exclusive access.
        unsafe { rows_mut(p, n) }
    }
    /// Damping of each degree of freedom (`dof_damping`).
    pub fn dof_damping(&self) -> &[f64] {
        let (p, n) = (self.raw().dof_damping, self.nv());
        // SAFETY: MuJoCo sizes dof_damping as nv reals.
        unsafe { rows::<f64, 1>(p, n) }.as_flattened()
    }
    /// Mutable `dof_damping`.
    pub fn dof_damping_mut(&mut self) -> &mut [f64] {
        let (p, n) = (self.raw_mut().dof_damping, self.nv());
        // SAFETY: as in `dof_damping`; `&mut self` gives exclusive access.
        unsafe { rows_mut::<f64, 1>(p, n) }.as_flattened_mut()
    }
    /// Mass of each body (`body_mass`).
    pub fn body_mass(&self) -> &[f64] {
        let (p, n) = (self.raw().body_mass, self.nbody());
        // SAFETY: MuJoCo sizes body_mass as nbody reals.
        unsafe { rows::<f64, 1>(p, n) }.as_flattened()
    }
    /// Mutable `body_mass`.
    pub fn body_mass_mut(&mut self) -> &mut [f64] {
        let (p, n) = (self.raw_mut().body_mass, self.nbody());
        // SAFETY: as in `body_mass`; `&mut self` gives exclusive access.
        unsafe { rows_mut::<f64, 1>(p, n) }.as_flattened_mut()
    }
    /// Diagonal inertia of each body in its inertial frame (`body_inertia`).
    pub fn body_inertia(&self) -> &[[f64; 3]] {
        let (p, n) = (self.raw().body_inertia, self.nbody());
        // SAFETY: MuJoCo sizes body_inertia as nbody × 3 reals.
        unsafe { rows(p, n) }
    }
    /// Mutable `body_inertia`.
    pub fn body_inertia_mut(&mut self) -> &mut [[f64; 3]] {
        let (p, n) = (self.raw_mut().body_inertia, self.nbody());
        // SAFETY: as in `body_inertia`; `&mut self` gives exclusive access.
        unsafe { rows_mut(p, n) }
    }

    fn ints(&self, p: *const i32, n: usize) -> &[i32] {
        // SAFETY: every caller passes a model array pointer together with the
        // model count that MuJoCo sized it with; the model outlives `&self`.
        unsafe { rows::<i32, 1>(p, n) }.as_flattened()
    }
}

/// `n` rows of `K` values at `p` (empty for none): a model array as MuJoCo lays it out.
///
/// # Safety
/// `p` is null or points to at least `n × K` initialised values that live, unchanged, as long as
/// the returned slice (a model array with the count MuJoCo sized it with).
unsafe fn rows<'a, T, const K: usize>(p: *const T, n: usize) -> &'a [[T; K]] {
    if n == 0 || p.is_null() {
        return &[];
    }
    // SAFETY: by the caller; [T; K] has the layout of K Ts.
    unsafe { std::slice::from_raw_parts(p as *const [T; K], n) }
}

/// As [`rows`], mutable.
///
/// # Safety
/// As [`rows`], and nothing else reads or writes the values while the slice lives.
unsafe fn rows_mut<'a, T, const K: usize>(p: *mut T, n: usize) -> &'a mut [[T; K]] {
    if n == 0 || p.is_null() {
        return &mut [];
    }
    // SAFETY: by the caller; [T; K] has the layout of K Ts.
    unsafe { std::slice::from_raw_parts_mut(p as *mut [T; K], n) }
}

impl Drop for Model {
    fn drop(&mut self) {
        // SAFETY: `ptr` came from mj_loadXML and is freed exactly once here.
        unsafe { sys::mj_deleteModel(self.ptr.as_ptr()) };
    }
}

impl std::fmt::Debug for Model {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Model")
            .field("nq", &self.nq())
            .field("nv", &self.nv())
            .field("nbody", &self.nbody())
            .field("ngeom", &self.ngeom())
            .finish()
    }
}

fn path_str(path: &Path) -> Result<&str, MjError> {
    path.to_str().ok_or_else(|| MjError::InvalidName { name: path.display().to_string(), reason: "not valid UTF-8" })
}
