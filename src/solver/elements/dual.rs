//! Forward-mode differentiation for kernels whose derivative is long to write by hand:
//! code written over [`Real`] runs on `f32` for values and on [`Dual`] for exact
//! directional derivatives of those values.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// The arithmetic a differentiable kernel may use.
pub trait Real:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> + Neg<Output = Self>
{
    /// A constant.
    fn constant(value: f32) -> Self;
    /// Square root.
    fn sqrt(self) -> Self;
    /// Four-quadrant arctangent of `self / x`.
    fn atan2(self, x: Self) -> Self;
}

impl Real for f32 {
    fn constant(value: f32) -> Self {
        value
    }
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    fn atan2(self, x: Self) -> Self {
        f32::atan2(self, x)
    }
}

/// A value with its derivative along one direction: `value + derivative · ε`, `ε² = 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dual {
    /// The value.
    pub value: f32,
    /// The directional derivative.
    pub derivative: f32,
}

impl Dual {
    /// A variable with a unit seed (`seed = 1`) or a passive one (`seed = 0`).
    pub fn new(value: f32, derivative: f32) -> Self {
        Self { value, derivative }
    }
}

impl Add for Dual {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self::new(self.value + o.value, self.derivative + o.derivative)
    }
}

impl Sub for Dual {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Self::new(self.value - o.value, self.derivative - o.derivative)
    }
}

impl Mul for Dual {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        Self::new(self.value * o.value, self.derivative * o.value + self.value * o.derivative)
    }
}

impl Div for Dual {
    type Output = Self;
    fn div(self, o: Self) -> Self {
        let value = self.value / o.value;
        Self::new(value, (self.derivative - value * o.derivative) / o.value)
    }
}

impl Neg for Dual {
    type Output = Self;
    fn neg(self) -> Self {
        Self::new(-self.value, -self.derivative)
    }
}

impl Real for Dual {
    fn constant(value: f32) -> Self {
        Self::new(value, 0.0)
    }
    fn sqrt(self) -> Self {
        let root = self.value.sqrt();
        Self::new(root, self.derivative / (2.0 * root))
    }
    fn atan2(self, x: Self) -> Self {
        let r2 = self.value * self.value + x.value * x.value;
        Self::new(self.value.atan2(x.value), (x.value * self.derivative - self.value * x.derivative) / r2)
    }
}

/// A 3-vector over any [`Real`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct V3<R>(pub [R; 3]);

impl<R: Real> V3<R> {
    /// Dot product.
    pub fn dot(self, o: Self) -> R {
        self.0[0] * o.0[0] + self.0[1] * o.0[1] + self.0[2] * o.0[2]
    }
    /// Cross product.
    pub fn cross(self, o: Self) -> Self {
        let [a, b] = [self.0, o.0];
        V3([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])
    }
    /// `self · s`.
    pub fn scale(self, s: R) -> Self {
        V3(self.0.map(|c| c * s))
    }
    /// Squared length.
    pub fn length_squared(self) -> R {
        self.dot(self)
    }
}

impl<R: Real> Add for V3<R> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        V3([self.0[0] + o.0[0], self.0[1] + o.0[1], self.0[2] + o.0[2]])
    }
}

impl<R: Real> Neg for V3<R> {
    type Output = Self;
    fn neg(self) -> Self {
        V3(self.0.map(|c| -c))
    }
}

impl<R: Real> Sub for V3<R> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        V3([self.0[0] - o.0[0], self.0[1] - o.0[1], self.0[2] - o.0[2]])
    }
}
