//! Print the describing function of the benchmark's Bouc-Wen element beside eqs. (19)+(20),
//! the table of `paper-errata.md` point 2: `cargo run -p hyst-linearize --example errata_table`.

use hyst_linearize::{describing_function, describing_function_first_order, paper, zener_at};
use hyst_model::{BoucWen, ZenerParams};

fn main() {
    let bw = BoucWen::benchmark();
    let w = 223.61;
    println!("| A (m) | K_eq | C_eq | first order K, C | eqs. (19)+(20): K, C of the Zener at ω |");
    println!("|---|---|---|---|---|");
    for a in [1e-4, 2.5e-4, 5e-4, 1e-3, 2.1e-3] {
        let d = describing_function(&bw, a).unwrap();
        let f = describing_function_first_order(&bw, a).unwrap();
        let z = ZenerParams {
            k_inf: paper::eq19_kinf(bw.alpha, bw.beta_delta(), a),
            omega: paper::eq20_omega(bw.beta_gamma(), bw.beta_delta(), a, w),
        };
        let p = zener_at(&z, w, a);
        println!(
            "| {a:e} | {:.0} | {:.2} | {:.0}, {:.2} | {:.0}, {:.2} |",
            d.stiffness,
            d.damping(w),
            f.stiffness,
            f.damping(w),
            p.stiffness,
            p.damping(w)
        );
    }
}
