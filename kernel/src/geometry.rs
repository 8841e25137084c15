//! Planar quantities in frame S of `plant.md`.
//!
//! Frame S: origin at the grasp point at t = 0 (arm extended on the table),
//! +x horizontal in the sagittal plane toward elbow and shoulder, +z up,
//! +y lateral (right-handed). `psi` is the forearm elevation: the angle of the
//! line elbow → grasp above the horizontal. All units SI: metres, radians,
//! seconds, newtons, newton-metres.

/// A point in the sagittal plane of frame S [m].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Point {
    /// Horizontal coordinate [m], toward the shoulder.
    pub x: f64,
    /// Vertical coordinate [m], up; the table is z = 0.
    pub z: f64,
}

impl Point {
    /// A point from its coordinates [m].
    pub const fn new(x: f64, z: f64) -> Self {
        Self { x, z }
    }

    /// Euclidean distance to `other` [m].
    pub fn distance(self, other: Point) -> f64 {
        libm::hypot(self.x - other.x, self.z - other.z)
    }

    /// True when both coordinates are finite.
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.z.is_finite()
    }
}

/// End-effector (grasp) pose in the sagittal plane of frame S.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Pose {
    /// Grasp-point horizontal position [m].
    pub x: f64,
    /// Grasp-point height above the table [m].
    pub z: f64,
    /// Forearm elevation [rad].
    pub psi: f64,
}

impl Pose {
    /// A pose from its coordinates [m, m, rad].
    pub const fn new(x: f64, z: f64, psi: f64) -> Self {
        Self { x, z, psi }
    }

    /// The grasp point of this pose.
    pub const fn point(self) -> Point {
        Point::new(self.x, self.z)
    }

    /// True when every coordinate is finite.
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.z.is_finite() && self.psi.is_finite()
    }
}

/// Rate of a [`Pose`]: [m/s, m/s, rad/s] (or its second derivative where the
/// field name says acceleration: [m/s², m/s², rad/s²]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct PoseRate {
    /// Horizontal component.
    pub x: f64,
    /// Vertical component.
    pub z: f64,
    /// Angular component.
    pub psi: f64,
}

impl PoseRate {
    /// Zero rate.
    pub const ZERO: PoseRate = PoseRate::new(0.0, 0.0, 0.0);

    /// A rate from its components.
    pub const fn new(x: f64, z: f64, psi: f64) -> Self {
        Self { x, z, psi }
    }

    /// Translational speed of the grasp point [m/s].
    pub fn linear_speed(self) -> f64 {
        libm::hypot(self.x, self.z)
    }

    /// True when every component is finite.
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.z.is_finite() && self.psi.is_finite()
    }
}

/// A planar wrench at the grasp point, frame S: forces [N] and the torque
/// about +y [N m].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Wrench {
    /// Horizontal force [N].
    pub fx: f64,
    /// Vertical force [N].
    pub fz: f64,
    /// Torque about +y [N m].
    pub ty: f64,
}

impl Wrench {
    /// No force, no torque.
    pub const ZERO: Wrench = Wrench::new(0.0, 0.0, 0.0);

    /// A wrench from its components [N, N, N m].
    pub const fn new(fx: f64, fz: f64, ty: f64) -> Self {
        Self { fx, fz, ty }
    }

    /// Magnitude of the force part [N].
    pub fn force_magnitude(self) -> f64 {
        libm::hypot(self.fx, self.fz)
    }

    /// True when every component is finite.
    pub fn is_finite(self) -> bool {
        self.fx.is_finite() && self.fz.is_finite() && self.ty.is_finite()
    }
}
/// Unsigned angle between `a` and `b` seen from `centre` [rad, 0..π].
pub fn angle_between(centre: Point, a: Point, b: Point) -> f64 {
    let (ax, az) = (a.x - centre.x, a.z - centre.z);
    let (bx, bz) = (b.x - centre.x, b.z - centre.z);
    libm::fabs(libm::atan2(ax * bz - az * bx, ax * bx + az * bz))
}
