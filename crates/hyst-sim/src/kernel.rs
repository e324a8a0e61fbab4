//! Specialised right-hand sides for the explicit integrator's hot loop.
//!
//! [`Oscillator::derivative`] handles every combination of terms through branches on a
//! 5-element state. The RK4 loop instead runs on a monomorphised kernel with only the states
//! in use and the constant factors precomputed: for the common cases (no extra forces) about
//! three times faster; for models with extra forces ([`Static`], and [`WithMass`] with a
//! second mass) the force terms are read once and the rare ones behind one flag, 1.7 times
//! faster than through `derivative` (a 26624-sample record at 4 sub-steps: 4.1 against
//! 7.1 ms with a cubic spring). The kernels are checked against `derivative` in this
//! module's tests.

use hyst_model::{Oscillator, Restoring, State};

/// `a·b + c`, fused into one instruction where the target has FMA (build with
/// `-C target-cpu=native`, as `.cargo/config.toml` does), else a plain multiply and add:
/// without hardware FMA, `f64::mul_add` is a slow library call.
#[inline(always)]
fn fma(a: f64, b: f64, c: f64) -> f64 {
    #[cfg(target_feature = "fma")]
    {
        a.mul_add(b, c)
    }
    #[cfg(not(target_feature = "fma"))]
    {
        a * b + c
    }
}

/// A first-order system on `N` states.
pub(crate) trait Kernel<const N: usize>: Sized {
    fn f(&self, s: &[f64; N], u: f64) -> [f64; N];
    /// The same system with every rate multiplied by `a` (each kernel's rates are linear
    /// in its constants, so this scales the constants once, outside the loop).
    fn scaled(&self, a: f64) -> Self;
    /// `base + f(s, u)`: the kernels fold `base` into the innermost sums, off the chain
    /// of dependent operations.
    #[inline(always)]
    fn f_plus(&self, base: &[f64; N], s: &[f64; N], u: f64) -> [f64; N] {
        let d = self.f(s, u);
        std::array::from_fn(|i| base[i] + d[i])
    }
    fn load(s: &State) -> [f64; N] {
        std::array::from_fn(|i| s[i])
    }
    fn store(s: &[f64; N]) -> State {
        let mut out = State::zeros();
        for (i, v) in s.iter().enumerate() {
            out[i] = *v;
        }
        out
    }
}

/// m ẍ + c ẋ + k x = u, as rates `[vx·v, inv_m·u + cm·v + km·x]`
/// (unscaled: vx = 1, cm = −c/m, km = −k/m).
pub(crate) struct Linear {
    vx: f64,
    inv_m: f64,
    cm: f64,
    km: f64,
}

impl Kernel<2> for Linear {
    #[inline(always)]
    fn f(&self, s: &[f64; 2], u: f64) -> [f64; 2] {
        self.f_plus(&[-0.0; 2], s, u)
    }
    fn scaled(&self, a: f64) -> Self {
        Linear {
            vx: a * self.vx,
            inv_m: a * self.inv_m,
            cm: a * self.cm,
            km: a * self.km,
        }
    }
    #[inline(always)]
    fn f_plus(&self, b: &[f64; 2], s: &[f64; 2], u: f64) -> [f64; 2] {
        let (x, v) = (s[0], s[1]);
        [
            fma(self.vx, v, b[0]),
            fma(self.cm, v, fma(self.km, x, fma(u, self.inv_m, b[1]))),
        ]
    }
}

/// The Bouc-Wen oscillator with ν = 1: rates `[vx·v, inv_m·u + km·x + cm·v + zm·z,
/// α·v − βδ·v·|z| − βγ·|v|·z]` (unscaled: vx = 1, cm = −c/m, km = −k/m, zm = −1/m).
pub(crate) struct BoucWen1 {
    vx: f64,
    inv_m: f64,
    cm: f64,
    km: f64,
    zm: f64,
    alpha: f64,
    bg: f64,
    bd: f64,
}

impl Kernel<3> for BoucWen1 {
    #[inline(always)]
    fn f(&self, s: &[f64; 3], u: f64) -> [f64; 3] {
        self.f_plus(&[-0.0; 3], s, u)
    }
    fn scaled(&self, a: f64) -> Self {
        BoucWen1 {
            vx: a * self.vx,
            inv_m: a * self.inv_m,
            cm: a * self.cm,
            km: a * self.km,
            zm: a * self.zm,
            alpha: a * self.alpha,
            bg: a * self.bg,
            bd: a * self.bd,
        }
    }
    #[inline(always)]
    fn f_plus(&self, b: &[f64; 3], s: &[f64; 3], u: f64) -> [f64; 3] {
        let (x, v, z) = (s[0], s[1], s[2]);
        // A shallow tree of fused multiply-adds: the RK4 stages are a chain of dependent
        // evaluations, so the latency of this expression sets the speed. The base and the
        // input enter innermost (known before the stage starts), x next (a stage earlier
        // than v and z), and z, the latest to arrive (its rate is the longest chain), last.
        let dv = fma(
            self.zm,
            z,
            fma(self.cm, v, fma(self.km, x, fma(u, self.inv_m, b[1]))),
        );
        let dz = fma(
            v,
            fma(self.bd, -z.abs(), self.alpha),
            fma(-self.bg * v.abs(), z, b[2]),
        );
        [fma(self.vx, v, b[0]), dv, dz]
    }
}

/// The Zener oscillator: rates `[vx·v, inv_m·u + km·x + cm·v + zm·z, k∞·v − Ω·z]`.
pub(crate) struct Zener {
    vx: f64,
    inv_m: f64,
    cm: f64,
    km: f64,
    zm: f64,
    k_inf: f64,
    omega: f64,
}

impl Kernel<3> for Zener {
    #[inline(always)]
    fn f(&self, s: &[f64; 3], u: f64) -> [f64; 3] {
        self.f_plus(&[-0.0; 3], s, u)
    }
    fn scaled(&self, a: f64) -> Self {
        Zener {
            vx: a * self.vx,
            inv_m: a * self.inv_m,
            cm: a * self.cm,
            km: a * self.km,
            zm: a * self.zm,
            k_inf: a * self.k_inf,
            omega: a * self.omega,
        }
    }
    #[inline(always)]
    fn f_plus(&self, b: &[f64; 3], s: &[f64; 3], u: f64) -> [f64; 3] {
        let (x, v, z) = (s[0], s[1], s[2]);
        [
            fma(self.vx, v, b[0]),
            fma(
                self.zm,
                z,
                fma(self.cm, v, fma(self.km, x, fma(u, self.inv_m, b[1]))),
            ),
            fma(self.k_inf, v, fma(-self.omega, z, b[2])),
        ]
    }
}

/// A model without a second mass, on its three states (x, ẋ, z): its extra forces are
/// functions of (x, ẋ) ([`hyst_model::ExtraForces::static_force`]) and its element any
/// (a Bouc-Wen element of any ν among them). Twice as fast as [`General`]'s five states.
pub(crate) struct Static<'a> {
    model: &'a Oscillator,
    /// The rates' scale a, and a/m.
    a: f64,
    a_inv_m: f64,
    /// c, k and the polynomial extra forces, read once.
    c: f64,
    k: f64,
    k3: f64,
    kq: f64,
    qd: f64,
    f0: f64,
    /// Whether any other extra force is on (clearance, friction, surface).
    rare: bool,
    elem: Element,
}

/// The restoring element's constants, read once.
#[derive(Clone, Copy)]
enum Element {
    None,
    BoucWen1 { alpha: f64, bg: f64, bd: f64 },
    Other,
}

impl<'a> Static<'a> {
    fn new(o: &'a Oscillator) -> Self {
        let e = &o.extras;
        Static {
            model: o,
            a: 1.0,
            a_inv_m: 1.0 / o.mass,
            c: o.damping,
            k: o.stiffness,
            k3: e.cubic_stiffness,
            kq: e.quadratic_stiffness,
            qd: e.quadratic_damping,
            f0: e.offset,
            rare: e.clearance.is_some() || e.coulomb.is_some() || e.surface.is_some(),
            elem: match &o.restoring {
                Restoring::None => Element::None,
                Restoring::BoucWen(b) if b.nu == 1.0 => Element::BoucWen1 {
                    alpha: b.alpha,
                    bg: b.beta_gamma(),
                    bd: b.beta_delta(),
                },
                _ => Element::Other,
            },
        }
    }
}

impl Kernel<3> for Static<'_> {
    #[inline(always)]
    fn f(&self, s: &[f64; 3], u: f64) -> [f64; 3] {
        let (x, v, z) = (s[0], s[1], s[2]);
        let mut force = u
            - self.f0
            - self.c * v
            - self.k * x
            - z
            - x * x * fma(self.k3, x, self.kq)
            - self.qd * v * v.abs();
        if self.rare {
            let e = &self.model.extras;
            if let Some(g) = &e.clearance {
                force -= g.force(x);
            }
            if let Some(cf) = &e.coulomb {
                force -= cf.force * (v / cf.smoothing_velocity).tanh();
            }
            if let Some(sf) = &e.surface {
                force -= sf.force(x, v);
            }
        }
        let dz = match self.elem {
            Element::None => 0.0,
            Element::BoucWen1 { alpha, bg, bd } => alpha * v - bg * v.abs() * z - bd * v * z.abs(),
            Element::Other => match &self.model.restoring {
                Restoring::BoucWen(b) => b.rate(v, z),
                Restoring::Zener(zp) => zp.k_inf * v - zp.omega * z,
                Restoring::None => 0.0,
            },
        };
        [self.a * v, self.a_inv_m * force, self.a * dz]
    }
    fn scaled(&self, a: f64) -> Self {
        Static {
            a: a * self.a,
            a_inv_m: a * self.a_inv_m,
            ..*self
        }
    }
}

/// [`Static`] with a second mass: the states (x, ẋ, z, x₂, ẋ₂), the coupling
/// k₂(x − x₂) + c₂(ẋ − ẋ₂) acting on both masses.
pub(crate) struct WithMass<'a> {
    main: Static<'a>,
    k2: f64,
    c2: f64,
    /// a/m₂.
    a_inv_m2: f64,
}

impl Kernel<5> for WithMass<'_> {
    #[inline(always)]
    fn f(&self, s: &[f64; 5], u: f64) -> [f64; 5] {
        let coupling = self.k2 * (s[0] - s[3]) + self.c2 * (s[1] - s[4]);
        let [dx, dv, dz] = self.main.f(&[s[0], s[1], s[2]], u - coupling);
        [dx, dv, dz, self.main.a * s[4], self.a_inv_m2 * coupling]
    }
    fn scaled(&self, a: f64) -> Self {
        WithMass {
            main: self.main.scaled(a),
            a_inv_m2: a * self.a_inv_m2,
            ..*self
        }
    }
}

/// Which kernel serves a model.
pub(crate) enum Choice<'a> {
    Linear(Linear),
    BoucWen1(BoucWen1),
    Zener(Zener),
    Static(Static<'a>),
    WithMass(WithMass<'a>),
}

pub(crate) fn choose(o: &Oscillator) -> Choice<'_> {
    let inv_m = 1.0 / o.mass;
    let (cm, km) = (-o.damping * inv_m, -o.stiffness * inv_m);
    if let Some(sm) = &o.extras.second_mass {
        return Choice::WithMass(WithMass {
            main: Static::new(o),
            k2: sm.stiffness,
            c2: sm.damping,
            a_inv_m2: 1.0 / sm.mass,
        });
    }
    if !o.extras.is_empty() {
        return Choice::Static(Static::new(o));
    }
    match &o.restoring {
        Restoring::None => Choice::Linear(Linear {
            vx: 1.0,
            inv_m,
            cm,
            km,
        }),
        Restoring::BoucWen(bw) if bw.nu == 1.0 => Choice::BoucWen1(BoucWen1 {
            vx: 1.0,
            inv_m,
            cm,
            km,
            zm: -inv_m,
            alpha: bw.alpha,
            bg: bw.beta_gamma(),
            bd: bw.beta_delta(),
        }),
        Restoring::Zener(z) => Choice::Zener(Zener {
            vx: 1.0,
            inv_m,
            cm,
            km,
            zm: -inv_m,
            k_inf: z.k_inf,
            omega: z.omega,
        }),
        Restoring::BoucWen(_) => Choice::Static(Static::new(o)),
    }
}

/// Classic RK4 with the step folded into the kernel's constants.
///
/// With Kᵢ = h/2·kᵢ computed by the kernel scaled by h/2, y₂ = y + K₁, y₃ = y + K₂ and, by
/// the kernel scaled by h, y₄ = y + h·k₃, the update y + h/6·(k₁ + 2k₂ + 2k₃ + k₄) equals
/// (y₂ − y + 2y₃ + y₄)/3 + K₄/3. The first three stages are then one call of
/// [`Kernel::f_plus`] each, with y folded into the innermost sums, and the sum of the first
/// three stages is formed while the last is evaluated: the chain of dependent operations
/// is three fused multiply-adds shorter per step than stage-by-stage `y + a·f(y)`.
/// llvm-mca (Sapphire Rapids) puts the Bouc-Wen loop at 48 cycles per step against 55 for
/// that form; a third scaled copy (h/6, to fold the last stage too) spills constants out
/// of registers and is slower.
pub(crate) struct Rk4<K> {
    half: K,
    full: K,
}

impl<K> Rk4<K> {
    pub(crate) fn new<const N: usize>(kernel: &K, h: f64) -> Self
    where
        K: Kernel<N>,
    {
        Rk4 {
            half: kernel.scaled(0.5 * h),
            full: kernel.scaled(h),
        }
    }

    /// One step from `y` with the input at the start, midpoint and end of the step.
    #[inline(always)]
    pub(crate) fn step<const N: usize>(&self, y: &[f64; N], u0: f64, um: f64, u1: f64) -> [f64; N]
    where
        K: Kernel<N>,
    {
        const THIRD: f64 = 1.0 / 3.0;
        let y2 = self.half.f_plus(y, y, u0);
        let y3 = self.half.f_plus(y, &y2, um);
        let y4 = self.full.f_plus(y, &y3, um);
        let base: [f64; N] =
            std::array::from_fn(|i| THIRD * (fma(2.0, y3[i], y2[i] - y[i]) + y4[i]));
        let k4 = self.half.f(&y4, u1);
        std::array::from_fn(|i| fma(THIRD, k4[i], base[i]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hyst_model::{BoucWen, ZenerParams};
    use proptest::prelude::*;

    fn check<const N: usize, K: Kernel<N>>(k: &K, o: &Oscillator, s: &State, u: f64) {
        let fast = k.f(&K::load(s), u);
        let slow = o.derivative(s, u);
        for i in 0..N {
            // Same terms in another order (and fused): agreement to rounding of the largest term.
            let scale = slow[i].abs() + 1e-9;
            assert!(
                (fast[i] - slow[i]).abs() <= 1e-12 * scale * 1e3,
                "{i}: {} vs {}",
                fast[i],
                slow[i]
            );
        }
    }

    /// Textbook RK4 on the general model's derivative.
    fn textbook_rk4(o: &Oscillator, s: &State, h: f64, u0: f64, um: f64, u1: f64) -> State {
        let k1 = o.derivative(s, u0);
        let k2 = o.derivative(&(s + k1 * (0.5 * h)), um);
        let k3 = o.derivative(&(s + k2 * (0.5 * h)), um);
        let k4 = o.derivative(&(s + k3 * h), u1);
        s + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0)
    }

    fn check_step<const N: usize, K: Kernel<N>>(
        k: &K,
        o: &Oscillator,
        s: &State,
        h: f64,
        u: [f64; 3],
    ) {
        let fast = Rk4::new(k, h).step(&K::load(s), u[0], u[1], u[2]);
        let slow = textbook_rk4(o, s, h, u[0], u[1], u[2]);
        // Size of the rates' terms: a rate that is a small difference of large terms is
        // rounded at the size of its terms in either form.
        let (x, v, z) = (s[0].abs(), s[1].abs(), s[2].abs());
        let ua = u.iter().fold(0.0f64, |m, w| m.max(w.abs()));
        let extra = match &o.restoring {
            Restoring::BoucWen(b) => {
                b.alpha * v + (b.beta_gamma().abs() + b.beta_delta().abs()) * v * z
            }
            Restoring::Zener(zp) => zp.k_inf * v + zp.omega * z,
            _ => 0.0,
        };
        let terms = h * (v + (ua + o.damping * v + o.stiffness * x + z) / o.mass + extra);
        for i in 0..N {
            // The folded form rounds y₂, y₃ and their sum (values of the state's size)
            // where the textbook form rounds only the increments: agreement to a few tens
            // of units of rounding of the state, its increment and the rates' terms.
            let scale = s[i].abs() + (slow[i] - s[i]).abs() + terms + 1e-12;
            assert!(
                (fast[i] - slow[i]).abs() <= 1e-14 * scale,
                "{i}: {} vs {}",
                fast[i],
                slow[i]
            );
        }
    }

    proptest! {
        // The folded RK4 step is the classic RK4 step.
        #[test]
        fn folded_step_is_classic_rk4(
            m in 0.1f64..10.0, c in 0.0f64..50.0, k in 1e3f64..1e5,
            alpha in 1e3f64..1e5, bg in -2e3f64..2e3, bd in -2e3f64..2e3,
            kinf in 1e3f64..2e5, om in 0.1f64..100.0, h in 1e-5f64..1e-3,
            x in -1e-2f64..1e-2, v in -1.0f64..1.0, z in -100.0f64..100.0,
            u0 in -100.0f64..100.0, um in -100.0f64..100.0, u1 in -100.0f64..100.0,
        ) {
            let s = State::new(x, v, z, 0.0, 0.0);
            let u = [u0, um, u1];
            let o = Oscillator::bouc_wen(m, c, k, BoucWen::from_products(alpha, bg, bd, 1.0));
            match choose(&o) { Choice::BoucWen1(kk) => check_step(&kk, &o, &s, h, u), _ => panic!("kernel choice") }
            let o = Oscillator::zener(m, c, k, ZenerParams { k_inf: kinf, omega: om });
            match choose(&o) { Choice::Zener(kk) => check_step(&kk, &o, &s, h, u), _ => panic!("kernel choice") }
            let o = Oscillator::linear(m, c, k);
            let s = State::new(x, v, 0.0, 0.0, 0.0);
            match choose(&o) { Choice::Linear(kk) => check_step(&kk, &o, &s, h, u), _ => panic!("kernel choice") }
        }

        // The specialised kernels compute the same derivative as the general model.
        #[test]
        fn kernels_agree_with_the_model(
            m in 0.1f64..10.0, c in 0.0f64..50.0, k in 1e3f64..1e5,
            alpha in 1e3f64..1e5, bg in -2e3f64..2e3, bd in -2e3f64..2e3,
            kinf in 1e3f64..2e5, om in 0.1f64..100.0,
            x in -1e-2f64..1e-2, v in -1.0f64..1.0, z in -100.0f64..100.0, u in -100.0f64..100.0,
        ) {
            let s = State::new(x, v, z, 0.0, 0.0);
            let o = Oscillator::bouc_wen(m, c, k, BoucWen::from_products(alpha, bg, bd, 1.0));
            match choose(&o) { Choice::BoucWen1(kk) => check(&kk, &o, &s, u), _ => panic!("kernel choice") }
            let o = Oscillator::zener(m, c, k, ZenerParams { k_inf: kinf, omega: om });
            match choose(&o) { Choice::Zener(kk) => check(&kk, &o, &s, u), _ => panic!("kernel choice") }
            // A linear oscillator has no z state (it stays at zero).
            let s = State::new(x, v, 0.0, 0.0, 0.0);
            let o = Oscillator::linear(m, c, k);
            match choose(&o) { Choice::Linear(kk) => check(&kk, &o, &s, u), _ => panic!("kernel choice") }
        }

        // The kernels of models with extra forces (and of a Bouc-Wen element of any ν)
        // compute the same derivative as the general model: every extra term, with and
        // without a second mass.
        #[test]
        fn extra_force_kernels_agree_with_the_model(
            m in 0.1f64..10.0, c in 0.0f64..50.0, k in 1e3f64..1e5,
            alpha in 1e3f64..1e5, bg in 0.0f64..2e3, bd in -2e3f64..2e3, nu in 0.5f64..3.0,
            k3 in -1e9f64..1e9, kq in -1e7f64..1e7, qd in 0.0f64..100.0,
            kg in 0.0f64..1e5, gap in 1e-4f64..5e-3, fc in 0.0f64..10.0,
            theta in proptest::array::uniform10(-5.0f64..5.0),
            m2 in 0.01f64..1.0, k2 in 1e2f64..1e5, c2 in 0.0f64..10.0,
            x in -1e-2f64..1e-2, v in -1.0f64..1.0, z in -100.0f64..100.0,
            x2 in -1e-2f64..1e-2, v2 in -1.0f64..1.0, u in -100.0f64..100.0,
            rare in any::<bool>(),
        ) {
            let mut o = Oscillator::bouc_wen(m, c, k, BoucWen::from_products(alpha, bg, bd, nu));
            o.extras.cubic_stiffness = k3;
            o.extras.quadratic_stiffness = kq;
            o.extras.quadratic_damping = qd;
            o.extras.offset = u / 3.0;
            if rare {
                o.extras.clearance = Some(hyst_model::Clearance { stiffness: kg, gap });
                o.extras.coulomb = Some(hyst_model::Coulomb { force: fc, smoothing_velocity: 0.05 });
                o.extras.surface = Some(hyst_model::ForceSurface {
                    x_scale: 2e-3, v_scale: 0.3, coefficients: theta,
                });
            }
            let s = State::new(x, v, z, 0.0, 0.0);
            match choose(&o) { Choice::Static(kk) => check(&kk, &o, &s, u), _ => panic!("kernel choice") }
            o.extras.second_mass = Some(hyst_model::SecondMass { mass: m2, stiffness: k2, damping: c2 });
            let s = State::new(x, v, z, x2, v2);
            match choose(&o) { Choice::WithMass(kk) => check(&kk, &o, &s, u), _ => panic!("kernel choice") }
        }
    }
}
