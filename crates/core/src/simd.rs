//! The one choice of CPU kernel for every SIMD path of the core, and the width of a packet.

/// Rays in a packet: the octree's packet traversal and the triangle packet pre-filter take
/// this many rays together (eight f32 lanes, one AVX2 register).
pub const PACKET: usize = 8;

/// Which implementation of the SIMD paths runs: the octree's node and leaf tests, the
/// triangle pre-filters and the instance bounds test. Every kernel gives the same answers,
/// bit for bit; the octree that starts a traversal chooses one
/// ([`crate::accel::Octree::with_kernel`]) and its rays carry it
/// ([`crate::accel::PreparedRay::kernel`]) into every test below, instanced meshes' octrees
/// included.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kernel {
    /// AVX2 with FMA (x86-64, chosen at run time when the CPU has both).
    Avx2,
    /// Plain Rust over `[f32; 8]` (a multiply and an add per plane), which the compiler
    /// vectorises for the target's baseline (SSE2, NEON).
    Portable,
}

impl Kernel {
    /// The fastest kernel this CPU runs.
    pub fn detect() -> Kernel {
        if Kernel::Avx2.available() {
            Kernel::Avx2
        } else {
            Kernel::Portable
        }
    }

    /// True when this CPU can run the kernel.
    pub fn available(self) -> bool {
        match self {
            Kernel::Portable => true,
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 => is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"),
            #[cfg(not(target_arch = "x86_64"))]
            Kernel::Avx2 => false,
        }
    }
}

/// Runs `f` compiled for AVX2 and FMA where the CPU has both ([`Kernel::Avx2`]): the fused
/// multiply-adds of what `f` inlines (the bounded arithmetic's exact product errors,
/// [`crate::bound::bounded`]) are then one instruction each rather than calls into the
/// runtime. The same bits either way: a fused multiply-add is correctly rounded on every CPU,
/// and the compiler neither fuses nor reorders other operations. `f` must be an
/// `#[inline(always)]` closure, and what it calls `#[inline(always)]` too: only code inlined
/// into `with_avx2_here` is compiled for AVX2.
#[inline(always)]
pub fn with_avx2<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if Kernel::Avx2.available() {
        // SAFETY: the CPU has AVX2 and FMA.
        return unsafe { with_avx2_here(f) };
    }
    f()
}

/// `f`, compiled for AVX2 and FMA (it is inlined here: its only caller).
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn with_avx2_here<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// Runs `$body` with `$kx`, `$ky`, `$kz` bound as constants to the axis permutation `$axes`
/// (a watertight ray's `[kx, ky, kz]`, one of the six): one compiled instance of `$body` per
/// permutation, so that picking a permuted coordinate in an AVX2 kernel is picking a field.
#[cfg(target_arch = "x86_64")]
macro_rules! per_axes {
    ($axes:expr, |$kx:ident, $ky:ident, $kz:ident| $body:expr) => {
        match $axes {
            [1, 2, 0] => per_axes!(@ 1, 2, 0, $kx, $ky, $kz, $body),
            [2, 1, 0] => per_axes!(@ 2, 1, 0, $kx, $ky, $kz, $body),
            [2, 0, 1] => per_axes!(@ 2, 0, 1, $kx, $ky, $kz, $body),
            [0, 2, 1] => per_axes!(@ 0, 2, 1, $kx, $ky, $kz, $body),
            [0, 1, 2] => per_axes!(@ 0, 1, 2, $kx, $ky, $kz, $body),
            _ => per_axes!(@ 1, 0, 2, $kx, $ky, $kz, $body),
        }
    };
    (@ $x:literal, $y:literal, $z:literal, $kx:ident, $ky:ident, $kz:ident, $body:expr) => {{
        const $kx: usize = $x;
        const $ky: usize = $y;
        const $kz: usize = $z;
        $body
    }};
}
#[cfg(target_arch = "x86_64")]
pub(crate) use per_axes;
