//! Copies of the hot kernels compiled for wider instruction sets, chosen at run time.
//!
//! The library is compiled for the baseline x86-64 (SSE2). A kernel whose body is an
//! `#[inline(always)]` function gets copies of that body compiled for wider instruction
//! sets, one function with `#[target_feature(enable = …)]` each, and a dispatching
//! function that calls the widest copy the CPU runs ([`Isa::detected`]). [`copies!`]
//! writes all of them from one declaration. The copies ([`Isa`]):
//!
//! - `Base`: the baseline body (SSE2, two lanes);
//! - `Avx`: the same body compiled for AVX (four lanes, VEX three-operand forms). No
//!   multiply–add is fused and no sum reordered, so it gives **the same bits as `Base`**;
//! - `Fma`: compiled for AVX2 and FMA; a body that asks for fused multiply–adds (a
//!   `Fused` type parameter) rounds each `c ± a b` once instead of twice: other
//!   round-off than `Base`, the same operations in the same order otherwise;
//! - `Avx512`: the `Fma` copy compiled with AVX-512 F and VL too (32 vector registers,
//!   masked moves): the same operations, so **the same bits as `Fma`**.
//!
//! A kernel declares the copies it has (always `Base`, and a prefix of the wider ones);
//! a CPU with a wider instruction set runs the widest declared one (an element declaring
//! `Base | Avx` runs its AVX copy on an AVX-512 CPU). Kernels called through `dyn` would
//! otherwise be compiled for the baseline only, whatever their callers are compiled for.

use std::sync::OnceLock;

/// A compiled copy of a kernel (see the [module](self) documentation); ordered by width.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Isa {
    /// The baseline (SSE2).
    Base,
    /// AVX: the same bits as `Base`.
    Avx,
    /// AVX2 and FMA: fused multiply–adds where the kernel asks for them.
    Fma,
    /// AVX-512 F and VL with AVX2 and FMA: the same bits as `Fma`.
    Avx512,
}

/// The environment variable that narrows the copies run (`base`, `avx`, `fma` or
/// `avx512`; [`Isa::detected`]): to profile under tools that do not decode the wider
/// instructions (valgrind 3.19 stops at a VEX `vmovq`), or to compare the copies' results
/// on one machine.
pub const ISA_VARIABLE: &str = "SAMARA_ISA";

impl Isa {
    /// The copy the kernels run, chosen once per process: the widest this CPU runs
    /// ([`Isa::cpu`]), narrowed to [`ISA_VARIABLE`] when that is set to a narrower one
    /// (a value that is not a copy's name is ignored here; the `samara` command refuses
    /// it, [`Isa::requested`]).
    pub fn detected() -> Self {
        static DETECTED: OnceLock<Isa> = OnceLock::new();
        *DETECTED.get_or_init(|| match Self::requested() {
            Ok(Some(r)) => r.min(Self::cpu()),
            _ => Self::cpu(),
        })
    }

    /// The widest copy this CPU runs.
    pub fn cpu() -> Self {
        static CPU: OnceLock<Isa> = OnceLock::new();
        *CPU.get_or_init(Self::detect)
    }

    /// The copy [`ISA_VARIABLE`] asks for: `None` when it is unset or empty, an error
    /// naming the accepted values when it is not one of them.
    pub fn requested() -> Result<Option<Self>, String> {
        match std::env::var(ISA_VARIABLE) {
            Err(std::env::VarError::NotPresent) => Ok(None),
            Err(std::env::VarError::NotUnicode(v)) => Err(format!(
                "{ISA_VARIABLE} = {v:?} is not text; expected one of base, avx, fma, avx512"
            )),
            Ok(v) if v.trim().is_empty() => Ok(None),
            Ok(v) => Self::parse(v.trim()).map(Some).ok_or_else(|| {
                format!(
                    "{ISA_VARIABLE} = \"{v}\" is not an instruction set samara has copies for; \
                     expected one of base, avx, fma, avx512"
                )
            }),
        }
    }

    /// The copy of a name (`base`, `avx`, `fma`, `avx512`, any case).
    pub fn parse(name: &str) -> Option<Self> {
        [Isa::Base, Isa::Avx, Isa::Fma, Isa::Avx512]
            .into_iter()
            .find(|i| i.name().eq_ignore_ascii_case(name))
    }

    /// The copy's name, as [`ISA_VARIABLE`] takes it.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Base => "base",
            Isa::Avx => "avx",
            Isa::Fma => "fma",
            Isa::Avx512 => "avx512",
        }
    }

    fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                if std::arch::is_x86_feature_detected!("avx512f")
                    && std::arch::is_x86_feature_detected!("avx512vl")
                {
                    return Isa::Avx512;
                }
                return Isa::Fma;
            }
            if std::arch::is_x86_feature_detected!("avx") {
                return Isa::Avx;
            }
        }
        Isa::Base
    }

    /// The widest of `copies` (a kernel's declared copies); `const` so that the
    /// dispatching functions fold it.
    pub const fn widest(copies: &[Isa]) -> Isa {
        let mut w = Isa::Base;
        let mut i = 0;
        while i < copies.len() {
            if copies[i] as u8 > w as u8 {
                w = copies[i];
            }
            i += 1;
        }
        w
    }
}

/// Declares a kernel's compiled copies and writes them with their dispatching function.
///
/// ```ignore
/// isa::copies! {
///     /// Solve `A x = b` in place.
///     pub fn solve_in_place(&mut self: BlockLu, rhs: &mut [f64]) where isa = self.isa {
///         Base | Avx => solve_impl::<Plain>,
///         Fma | Avx512 => solve_impl::<Fused>,
///     }
/// }
/// ```
///
/// writes the method `solve_in_place(&mut self, rhs)` and, inside it, one function per
/// wider copy (named after it: `solve_in_place::Avx`, … in profiles) compiled for its
/// instruction set, whose body is the call of the `#[inline(always)]` function given
/// (with the same arguments, generic arguments per copy). The method runs the widest
/// declared copy no wider than `Isa::detected()` and the selector (`where isa =
/// self.FIELD`; without it the detected one alone), so every copy runs only on a CPU
/// that has its features. Forms:
///
/// - methods: `fn name(&self: Type, args…)` or `(&mut self: Type, …)` (`Type` is `Self`
///   spelled out: the copies are functions inside the method, which cannot name `Self`;
///   lifetimes elided as `Type<'_>`), optional `-> Ret`, optional selector;
/// - free functions: `unsafe fn name(isa: Isa, args…)`: the selector is the first
///   argument, the copies get the others and the caller's safety contract.
///
/// The first arm starts with `Base`; the copies are `Base`, `Avx`, `Fma`, `Avx512`.
macro_rules! copies {
    // A method on `&self` or `&mut self`.
    (
        $(#[$attr:meta])*
        $vis:vis fn $name:ident(&self: $sty:ty $(, $arg:ident: $aty:ty)* $(,)?)
        $(-> $ret:ty)? $(where isa = self.$field:ident)?
        { $($arms:tt)* }
    ) => {
        $crate::math::isa::copies!(@method [$(#[$attr])*] $vis $name [&] $sty
            [$($arg: $aty),*] [$($ret)?] [$($field)?] { $($arms)* });
    };
    (
        $(#[$attr:meta])*
        $vis:vis fn $name:ident(&mut self: $sty:ty $(, $arg:ident: $aty:ty)* $(,)?)
        $(-> $ret:ty)? $(where isa = self.$field:ident)?
        { $($arms:tt)* }
    ) => {
        $crate::math::isa::copies!(@method [$(#[$attr])*] $vis $name [&mut] $sty
            [$($arg: $aty),*] [$($ret)?] [$($field)?] { $($arms)* });
    };
    (@method [$($attr:tt)*] $vis:vis $name:ident [$($refm:tt)+] $sty:ty
        [$($arg:ident: $aty:ty),*] [$($ret:ty)?] [$($field:ident)?]
        {
            Base $(| $copy0:ident)* => $call0:ident $(::<$($g0:tt),+>)?
            $(, $($copy:ident)|+ => $call:ident $(::<$($g:tt),+>)?)* $(,)?
        }
    ) => {
        $($attr)*
        $vis fn $name($($refm)+ self $(, $arg: $aty)*) $(-> $ret)? {
            #[cfg_attr(not(target_arch = "x86_64"), allow(unused_variables))]
            let isa = $crate::math::isa::copies!(@select
                [Base $(, $copy0)* $($(, $copy)+)*] [$(self.$field)?]);
            $crate::math::isa::copies!(@groups
                {isa, (this: $($refm)+ $sty $(, $arg: $aty)*), [$($ret)?], [this.],
                    (self $(, $arg)*), ($($arg),*), []};
                [$($copy0),*] [$call0 $(::<$($g0),+>)?]
                $([$($copy),+] [$call $(::<$($g),+>)?])*);
            self.$call0$(::<$($g0),+>)?($($arg),*)
        }
    };
    // A free `unsafe fn` whose first argument selects the copy.
    (
        $(#[$attr:meta])*
        $vis:vis unsafe fn $name:ident($sel:ident: Isa $(, $arg:ident: $aty:ty)* $(,)?)
        $(-> $ret:ty)?
        {
            Base $(| $copy0:ident)* => $call0:ident $(::<$($g0:tt),+>)?
            $(, $($copy:ident)|+ => $call:ident $(::<$($g:tt),+>)?)* $(,)?
        }
    ) => {
        $(#[$attr])*
        $vis unsafe fn $name($sel: $crate::math::isa::Isa $(, $arg: $aty)*) $(-> $ret)? {
            #[cfg_attr(not(target_arch = "x86_64"), allow(unused_variables))]
            let isa = $crate::math::isa::copies!(@select
                [Base $(, $copy0)* $($(, $copy)+)*] [$sel]);
            $crate::math::isa::copies!(@groups
                {isa, ($($arg: $aty),*), [$($ret)?], [], ($($arg),*), ($($arg),*), [unsafe]};
                [$($copy0),*] [$call0 $(::<$($g0),+>)?]
                $([$($copy),+] [$call $(::<$($g),+>)?])*);
            // SAFETY: the caller's.
            unsafe { $call0$(::<$($g0),+>)?($($arg),*) }
        }
    };
    // The copy to run: the widest declared one within the CPU's and the selector's.
    (@select [$($copy:ident),+] [$($sel:expr)?]) => {{
        const WIDEST: $crate::math::isa::Isa =
            $crate::math::isa::Isa::widest(&[$($crate::math::isa::Isa::$copy),+]);
        #[allow(unused_mut)]
        let mut isa = $crate::math::isa::Isa::detected().min(WIDEST);
        $(isa = isa.min($sel);)?
        isa
    }};
    // The wider copies, group by group (the copies of a group share the call).
    (@groups $ctx:tt;) => {};
    (@groups $ctx:tt; [$($copy:ident),*] $call:tt $($rest:tt)*) => {
        $($crate::math::isa::copies!(@copy $copy $ctx $call);)*
        $crate::math::isa::copies!(@groups $ctx; $($rest)*);
    };
    (@copy Avx $($rest:tt)*) => {
        $crate::math::isa::copies!(@copy_for "avx", Avx $($rest)*);
    };
    (@copy Fma $($rest:tt)*) => {
        $crate::math::isa::copies!(@copy_for "avx,avx2,fma", Fma $($rest)*);
    };
    (@copy Avx512 $($rest:tt)*) => {
        $crate::math::isa::copies!(@copy_for "avx,avx2,fma,avx512f,avx512vl", Avx512 $($rest)*);
    };
    // One wider copy and its call (returns from the dispatching function).
    (@copy_for $features:literal, $copy:ident
        {$isa:ident, ($($param:tt)*), [$($ret:ty)?], [$($recv:tt)*], ($($arg:tt)*),
            ($($callarg:tt)*), []}
        [$($call:tt)*]
    ) => {
        #[cfg(target_arch = "x86_64")]
        {
            #[target_feature(enable = $features)]
            #[allow(non_snake_case, clippy::too_many_arguments)]
            fn $copy($($param)*) $(-> $ret)? {
                $($recv)* $($call)*($($callarg)*)
            }
            if $isa == $crate::math::isa::Isa::$copy {
                // SAFETY: `isa` ≤ `Isa::detected()` ≤ `Isa::cpu()`: the CPU has the copy's
                // features.
                return unsafe { $copy($($arg)*) };
            }
        }
    };
    (@copy_for $features:literal, $copy:ident
        {$isa:ident, ($($param:tt)*), [$($ret:ty)?], [], ($($arg:tt)*),
            ($($callarg:tt)*), [unsafe]}
        [$($call:tt)*]
    ) => {
        #[cfg(target_arch = "x86_64")]
        {
            #[target_feature(enable = $features)]
            #[allow(non_snake_case, clippy::too_many_arguments)]
            unsafe fn $copy($($param)*) $(-> $ret)? {
                // SAFETY: the caller's.
                unsafe { $($call)*($($callarg)*) }
            }
            if $isa == $crate::math::isa::Isa::$copy {
                // SAFETY: `isa` ≤ `Isa::detected()` ≤ `Isa::cpu()`: the CPU has the copy's
                // features; the rest is the caller's.
                return unsafe { $copy($($arg)*) };
            }
        }
    };
}

pub(crate) use copies;

#[cfg(test)]
mod tests {
    use super::Isa;

    #[test]
    fn names_parse_back_and_the_order_is_by_width() {
        for isa in [Isa::Base, Isa::Avx, Isa::Fma, Isa::Avx512] {
            assert_eq!(Isa::parse(isa.name()), Some(isa));
            assert_eq!(Isa::parse(&isa.name().to_uppercase()), Some(isa));
        }
        assert_eq!(Isa::parse("sse2"), None);
        assert_eq!(Isa::parse(""), None);
        assert!(Isa::Base < Isa::Avx && Isa::Avx < Isa::Fma && Isa::Fma < Isa::Avx512);
        assert!(Isa::detected() <= Isa::cpu());
    }
}
