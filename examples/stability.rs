//! The stability report: runs every extreme case of `tests/stability` and prints a Markdown table.
//!
//! `cargo run --release --example stability` prints one row per case: status, iterations,
//! final residual, relative time error against the case's exact reference, and the 2-norm
//! condition of the Hessian at the solution (`-` where there is no reference or no smooth
//! solution). `-- --dump NAME` prints the scene of case `NAME` instead (a reproduction for
//! `eigenray solve`).

#[path = "../tests/stability/cases.rs"]
mod cases;

use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let [flag, name] = args.as_slice()
        && flag == "--dump"
    {
        println!("{}", cases::by_name(name).json);
        return;
    }
    let start = Instant::now();
    println!("{}", cases::TABLE_HEADER);
    let mut failed = Vec::new();
    let mut notes = Vec::new();
    for (name, _) in cases::CASES {
        let case = cases::by_name(name);
        let out = cases::run(&case);
        println!("{}", out.row(name));
        let found = if (3..=4).contains(&out.ray.points.len()) {
            let inner: Vec<String> = out.ray.points[1..out.ray.points.len() - 1]
                .iter()
                .map(|p| format!("({:.6}, {:.6})", p.x, p.y))
                .collect();
            format!(" → {} at {}", out.ray.status, inner.join(", "))
        } else {
            String::new()
        };
        notes.push(format!("- **{name}**: {}{found}", case.what));
        if !out.failures.is_empty() {
            failed.push((*name, case.what, out.failures));
        }
    }
    println!();
    println!(
        "{} cases in {:.2} s, {} failed.",
        cases::CASES.len(),
        start.elapsed().as_secs_f64(),
        failed.len()
    );
    println!("\nThe cases:\n");
    for n in notes {
        println!("{n}");
    }
    for (name, what, failures) in failed {
        println!("\n**{name}** ({what}):");
        for f in failures {
            println!("- {f}");
        }
    }
}
