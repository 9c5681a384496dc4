//! `cargo xtask report --quick`, run in-process: the committed error figures in
//! `docs/report/error-vs-runtime.csv` and `control-block.csv` must be what fresh runs print, digit
//! for digit (the errors are deterministic, reproduced bit for bit by the same binary on the same
//! machine; only the run times depend on timing, and they are not compared; rows the report marks
//! as sensitive to rounding are left out, see `QUICK_MAX_SENSITIVITY`), and a small seeded
//! stability sweep must show no failure; the committed README.md and stability.md must be what the
//! committed data files give. Tampered copies of the CSVs (the error table and the control-block
//! table), each moved by one unit of its last printed place, must be caught, and so must a README
//! changed by hand.

use std::fs;
use std::path::{Path, PathBuf};

use xtask::report::{ReportError, quick_check};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

#[test]
fn committed_error_figures_are_what_fresh_runs_print() {
    let (root, mut out, mut err) = (root(), Vec::new(), Vec::new());
    let args = ["report", "--quick", "--scenes", "scenes", "--out", "docs/report"];
    let args: Vec<std::ffi::OsString> = args
        .iter()
        .map(|a| if a.contains('/') || *a == "scenes" { root.join(a).into_os_string() } else { a.into() })
        .collect();
    let code = xtask::run(args, &mut out, &mut err);
    let (out, err) = (String::from_utf8_lossy(&out), String::from_utf8_lossy(&err));
    println!("{out}{err}");
    assert_eq!(code, 0, "report --quick failed:\n{err}");
    assert!(out.starts_with("report --quick: "), "{out}");
}

/// One unit of the last printed place of an error (the CSVs print 4 decimals): the smallest
/// change a committed figure can show.
const LAST_PLACE: f64 = 1e-4;

#[test]
fn an_error_figure_moved_by_one_unit_of_its_last_printed_place_is_caught() {
    let root = root();
    let committed = fs::read_to_string(root.join("docs/report/error-vs-runtime.csv")).expect("the committed CSV");
    // Move the Fig. 5 QSA N = 6 error against IMP at the base rate by one unit of the last place.
    let mut lines: Vec<String> = committed.lines().map(str::to_owned).collect();
    let header: Vec<&str> = lines[0].split(',').collect();
    let column = header.iter().position(|h| *h == "error_vs_imp").expect("an error_vs_imp column");
    let row = lines.iter().position(|l| l.starts_with("fig5-hammer,qsa,6,1,")).expect("the Fig. 5 N = 6 row");
    let mut fields: Vec<String> = lines[row].split(',').map(str::to_owned).collect();
    let value: f64 = fields[column].parse().expect("a number");
    fields[column] = format!("{:.4}", value + LAST_PLACE);
    lines[row] = fields.join(",");
    let dir = copy_of_the_report();
    fs::write(dir.path().join("error-vs-runtime.csv"), lines.join("\n") + "\n").expect("write the copy");
    // Move the glide's QSA output error at N_b = 64 by one unit of the last place.
    let blocks = fs::read_to_string(root.join("docs/report/control-block.csv")).expect("the committed CSV");
    let blocks: Vec<String> = blocks
        .lines()
        .map(|l| match l.strip_prefix("glide,qsa,5,64,") {
            Some(rest) => {
                let mut fields: Vec<String> = rest.split(',').map(str::to_owned).collect();
                let value: f64 = fields[0].parse().expect("a number");
                fields[0] = format!("{:.4}", value + LAST_PLACE);
                format!("glide,qsa,5,64,{}", fields.join(","))
            }
            None => l.to_owned(),
        })
        .collect();
    fs::write(dir.path().join("control-block.csv"), blocks.join("\n") + "\n").expect("write the copy");
    match quick_check(&root.join("scenes"), dir.path()) {
        Err(ReportError::Mismatch(count, message)) => {
            println!("{message}");
            assert!(message.contains("fig5-hammer qsa N=6 1x: error_vs_imp"), "{message}");
            assert!(message.contains("glide/qsa/N_b 64: output error"), "{message}");
            // The texts made from the tampered data may differ too (the fitted orders print 4
            // decimals); nothing else may.
            let derived = message.lines().filter(|l| l.starts_with("convergence.csv:")).count();
            assert_eq!(count, 2 + derived, "{message}");
        }
        other => panic!("expected the two moved figures to be caught, got {other:?}"),
    }
}

/// A temporary copy of the committed report's text and data files.
fn copy_of_the_report() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("a temporary directory");
    for entry in fs::read_dir(root().join("docs/report")).expect("the report directory") {
        let path = entry.expect("an entry").path();
        if path.extension().is_some_and(|e| e == "csv" || e == "md") {
            fs::copy(&path, dir.path().join(path.file_name().expect("a name"))).expect("copy");
        }
    }
    dir
}

#[test]
fn a_readme_figure_typed_by_hand_is_caught() {
    let root = root();
    let dir = copy_of_the_report();
    let readme = fs::read_to_string(dir.path().join("README.md")).expect("the committed README");
    // Change the first run time the README prints ("RTF 1.39e-3" becomes "RTF 1.38e-3", say).
    let at = readme.find("RTF ").expect("a run time in the README") + 4;
    let digit = readme[at..].chars().next().expect("a digit");
    let other = if digit == '1' { '2' } else { '1' };
    let edited = format!("{}{other}{}", &readme[..at], &readme[at + 1..]);
    fs::write(dir.path().join("README.md"), edited).expect("write the copy");
    match quick_check(&root.join("scenes"), dir.path()) {
        Err(ReportError::Mismatch(1, message)) => {
            println!("{message}");
            assert!(message.starts_with("README.md: line "), "{message}");
        }
        other => panic!("expected exactly one mismatch, in README.md, got {other:?}"),
    }
}
