//! The machine and the run that measured the report's timings: `run.csv`.
//!
//! Run times mean something only with the machine they were measured on, so the full report
//! records the CPU's model name (from `/proc/cpuinfo` where the system has one), the kernel level
//! the string code picked at run time ([`qsa_dsp::string::Isa::detect`], the level
//! `cargo xtask bench` prints), the logical CPUs, the commit the sources were at (`git rev-parse`,
//! with `+changes` when the work tree differed from it) and the wall time of each part of the run.
//! The README prints these from the file, so `--quick` and `--from-data` can regenerate its text
//! without timing anything.

use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;

/// The machine and the run, as `run.csv` stores them.
#[derive(Debug, Clone, PartialEq)]
pub struct RunInfo {
    /// CPU model name, or `unknown CPU`.
    pub cpu: String,
    /// The string kernels' instruction-set level picked at run time (e.g. `Avx512`).
    pub kernels: String,
    /// Logical CPUs available to the process.
    pub cpus: usize,
    /// The commit the report was generated at (`+changes` if the work tree differed).
    pub commit: String,
    /// Wall time of the error sweep: renders, timing and the sensitivity runs (s).
    pub error_seconds: f64,
    /// Wall time of the stability sweep (s).
    pub stability_seconds: f64,
    /// Wall time of the whole run, plots included (s).
    pub total_seconds: f64,
}

/// The CPU's model name from `/proc/cpuinfo`'s first `model name` line, if there is one.
pub fn cpu_model() -> Option<String> {
    let text = std::fs::read_to_string("/proc/cpuinfo").ok()?;
    text.lines()
        .find_map(|l| l.strip_prefix("model name").and_then(|rest| rest.split_once(':')).map(|(_, v)| v.trim()))
        .filter(|v| !v.is_empty())
        .map(str::to_owned)
}

/// The commit of the repository at `root` (short hash), with `+changes` if tracked files outside
/// `root` differ from it (the report directory `root` holds the files this run rewrites);
/// `unknown` without git.
pub fn commit(root: &Path) -> String {
    let git = |args: &[&str]| {
        Command::new("git")
            .arg("-C")
            .arg(root)
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_owned())
    };
    match git(&["rev-parse", "--short=12", "HEAD"]) {
        Some(hash) => match git(&["status", "--porcelain", "--untracked-files=no", "--", ":/", ":(exclude)."]) {
            Some(changes) if !changes.is_empty() => format!("{hash}+changes"),
            _ => hash,
        },
        None => "unknown".to_owned(),
    }
}

impl RunInfo {
    /// This machine, with the given wall times (s), at the commit of the repository at `root`.
    pub fn this_machine(root: &Path, error_seconds: f64, stability_seconds: f64, total_seconds: f64) -> Self {
        Self {
            cpu: cpu_model().unwrap_or_else(|| "unknown CPU".to_owned()),
            kernels: format!("{:?}", qsa_dsp::string::Isa::detect()),
            cpus: std::thread::available_parallelism().map_or(1, |n| n.get()),
            commit: commit(root),
            error_seconds,
            stability_seconds,
            total_seconds,
        }
    }

    /// `run.csv`: one `key,value` line per field (values without commas).
    pub fn to_csv(&self) -> String {
        let mut out = String::from("key,value\n");
        let clean = |v: &str| v.replace(',', ";");
        let _ = writeln!(out, "cpu,{}", clean(&self.cpu));
        let _ = writeln!(out, "kernels,{}", clean(&self.kernels));
        let _ = writeln!(out, "cpus,{}", self.cpus);
        let _ = writeln!(out, "commit,{}", clean(&self.commit));
        let _ = writeln!(out, "error_seconds,{:.1}", self.error_seconds);
        let _ = writeln!(out, "stability_seconds,{:.1}", self.stability_seconds);
        let _ = writeln!(out, "total_seconds,{:.1}", self.total_seconds);
        out
    }

    /// Read what [`Self::to_csv`] wrote.
    pub fn parse_csv(text: &str) -> Result<Self, String> {
        let mut lines = text.lines();
        if lines.next() != Some("key,value") {
            return Err("the first line must be key,value".into());
        }
        let pairs: Vec<(&str, &str)> = lines.filter_map(|l| l.split_once(',')).collect();
        let get = |key: &str| pairs.iter().find(|(k, _)| *k == key).map(|(_, v)| *v).ok_or(format!("no {key}"));
        let number = |key: &str| get(key)?.parse::<f64>().map_err(|e| format!("{key}: {e}"));
        Ok(Self {
            cpu: get("cpu")?.to_owned(),
            kernels: get("kernels")?.to_owned(),
            cpus: get("cpus")?.parse().map_err(|e| format!("cpus: {e}"))?,
            commit: get("commit")?.to_owned(),
            error_seconds: number("error_seconds")?,
            stability_seconds: number("stability_seconds")?,
            total_seconds: number("total_seconds")?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_csv_reads_back_what_it_wrote() {
        let info = RunInfo {
            cpu: "Some CPU, 2 GHz".into(),
            kernels: "Avx512".into(),
            cpus: 2,
            commit: "0123456789ab+changes".into(),
            error_seconds: 27.04,
            stability_seconds: 376.0,
            total_seconds: 411.26,
        };
        let back = RunInfo::parse_csv(&info.to_csv()).unwrap();
        assert_eq!(back.cpu, "Some CPU; 2 GHz", "a comma in a value is replaced, not split on");
        assert_eq!((back.cpus, back.kernels.as_str(), back.commit.as_str()), (2, "Avx512", "0123456789ab+changes"));
        assert!((back.total_seconds - 411.3).abs() < 1e-9, "times are kept to 0.1 s");
        assert_eq!(back.to_csv(), RunInfo::parse_csv(&back.to_csv()).unwrap().to_csv());
    }
}
