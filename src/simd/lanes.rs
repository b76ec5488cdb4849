//! Four f64 lanes ([`F4`]): one value of four independent evaluations side by side, for
//! kernels that run the same operations on four intervals at once (the interval block's
//! lane kernel, `collocation/interval_lanes.rs`).
//!
//! Every operator is element-wise and `#[inline(always)]`: in a function compiled with AVX2
//! (`avx2_fma!`) LLVM turns each into one `vaddpd`/`vmulpd`/`vdivpd` on a 256-bit register.
//! Each lane does the IEEE operation the scalar code does on its value (Rust never
//! contracts a product and a sum into an FMA), so a lane gives the scalar code's bits when
//! the lane kernel performs the scalar kernel's operations in the same order.

use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// Four f64 values, one per lane, aligned for 256-bit loads and stores.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct F4(pub(crate) [f64; 4]);

impl F4 {
    /// All four lanes `x`.
    #[inline(always)]
    pub(crate) const fn splat(x: f64) -> Self {
        F4([x; 4])
    }

    /// All lanes zero.
    pub(crate) const ZERO: F4 = F4::splat(0.0);

    /// Lane `i` (0..4).
    #[inline(always)]
    pub(crate) fn lane(self, i: usize) -> f64 {
        self.0[i]
    }

    /// `f` applied to each lane (a call per lane: libm's functions, a branch per lane).
    #[inline(always)]
    pub(crate) fn map(self, f: impl Fn(f64) -> f64) -> Self {
        F4([f(self.0[0]), f(self.0[1]), f(self.0[2]), f(self.0[3])])
    }

    /// The square root of each lane (exact, as `f64::sqrt`).
    #[inline(always)]
    pub(crate) fn sqrt(self) -> Self {
        self.map(f64::sqrt)
    }
}

/// An element-wise binary operator and its assigning form.
macro_rules! lanewise {
    ($trait:ident, $method:ident, $assign:ident, $assign_method:ident, $op:tt) => {
        impl $trait for F4 {
            type Output = F4;
            #[inline(always)]
            fn $method(self, o: F4) -> F4 {
                F4([self.0[0] $op o.0[0], self.0[1] $op o.0[1], self.0[2] $op o.0[2], self.0[3] $op o.0[3]])
            }
        }
        impl $trait<f64> for F4 {
            type Output = F4;
            #[inline(always)]
            fn $method(self, o: f64) -> F4 {
                self $op F4::splat(o)
            }
        }
        impl $assign for F4 {
            #[inline(always)]
            fn $assign_method(&mut self, o: F4) {
                *self = *self $op o;
            }
        }
    };
}

lanewise!(Add, add, AddAssign, add_assign, +);
lanewise!(Sub, sub, SubAssign, sub_assign, -);
lanewise!(Mul, mul, MulAssign, mul_assign, *);
lanewise!(Div, div, DivAssign, div_assign, /);

use std::ops::DivAssign;

impl Neg for F4 {
    type Output = F4;
    #[inline(always)]
    fn neg(self) -> F4 {
        F4([-self.0[0], -self.0[1], -self.0[2], -self.0[3]])
    }
}

#[cfg(test)]
mod tests {
    use super::F4;

    /// Each lane of every operator is the scalar operation on that lane's values, bit for
    /// bit (values with inexact sums, products and quotients, a signed zero).
    #[test]
    fn lanes_give_the_scalar_bits() {
        let a = [0.1, -3.7e-9, 1.0 / 3.0, -0.0];
        let b = [7.3, 2.9e5, -1e-300, 0.0];
        let (x, y) = (F4(a), F4(b));
        for i in 0..4 {
            assert_eq!((x + y).lane(i).to_bits(), (a[i] + b[i]).to_bits());
            assert_eq!((x - y).lane(i).to_bits(), (a[i] - b[i]).to_bits());
            assert_eq!((x * y).lane(i).to_bits(), (a[i] * b[i]).to_bits());
            assert_eq!((y / x).lane(i).to_bits(), (b[i] / a[i]).to_bits());
            assert_eq!((-x).lane(i).to_bits(), (-a[i]).to_bits());
            assert_eq!(y.sqrt().lane(i).to_bits(), b[i].sqrt().to_bits());
        }
    }
}
