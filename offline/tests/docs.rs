//! The documentation names only commands that exist: every `prf …` command shown in README.md
//! and docs/*.md (code blocks and inline code) is checked against `prf … --help` — each
//! subcommand must be listed by its parent, each flag by its subcommand. A doc that names a
//! removed subcommand or flag fails here.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The documents a user reads: README.md and docs/*.md (the changelog is history and keeps
/// the names of its day; docs/benchmarks.md is what `scripts/bench-report.sh` ran and printed,
/// so its commands ran when it was written).
fn documents() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut docs = vec![root.join("README.md")];
    let mut more: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .expect("docs/")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .filter(|p| !p.ends_with("benchmarks.md"))
        .collect();
    more.sort();
    docs.extend(more);
    docs
}

/// A `prf` command found in a document: where, and its words after `prf`.
#[derive(Debug)]
struct Shown {
    at: String,
    words: Vec<String>,
}

/// The shell words of `text` that follow each word `prf` (or `…/prf`), up to the end of the
/// command (a pipe, `&&`, `;`, a redirection or a comment).
fn commands_in(text: &str, at: &str, out: &mut Vec<Shown>) {
    let words: Vec<&str> = text.split_whitespace().collect();
    for (i, w) in words.iter().enumerate() {
        if !(*w == "prf" || w.ends_with("/prf")) {
            continue;
        }
        let mut cmd = Vec::new();
        for w in &words[i + 1..] {
            if ["|", "&&", "||", ";", "&", "#"].contains(w)
                || w.starts_with('>')
                || w.starts_with("2>")
            {
                break;
            }
            cmd.push(w.to_string());
        }
        // `cargo run … --bin prf -- demo`.
        if cmd.first().is_some_and(|w| w == "--") {
            cmd.remove(0);
        }
        out.push(Shown {
            at: at.to_string(),
            words: cmd,
        });
    }
}

/// Every `prf` command of a Markdown document: in fenced code blocks (continued lines joined)
/// and in inline code.
fn commands_of(path: &Path) -> Vec<Shown> {
    let text = std::fs::read_to_string(path).expect("read a document");
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    let mut out = Vec::new();
    let mut fenced = false;
    let mut pending = String::new();
    for (n, line) in text.lines().enumerate() {
        let at = format!("{name}:{}", n + 1);
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            let line = line.trim_start_matches("$ ");
            if let Some(head) = line.strip_suffix('\\') {
                pending += head;
                pending.push(' ');
                continue;
            }
            let whole = std::mem::take(&mut pending) + line;
            commands_in(&whole, &at, &mut out);
        } else {
            for (k, span) in line.split('`').enumerate() {
                if k % 2 == 1 {
                    commands_in(span, &at, &mut out);
                }
            }
        }
    }
    out
}

/// `prf PATH… --help`, cached.
struct Helps(HashMap<Vec<String>, String>);

impl Helps {
    fn of(&mut self, path: &[String]) -> &str {
        self.0.entry(path.to_vec()).or_insert_with(|| {
            let out = Command::new(env!("CARGO_BIN_EXE_prf"))
                .args(path)
                .arg("--help")
                .output()
                .expect("start prf");
            assert!(out.status.success(), "prf {path:?} --help failed");
            String::from_utf8_lossy(&out.stdout).into_owned()
        })
    }
}

/// The subcommands a help text lists (its "Commands:" section).
fn subcommands(help: &str) -> Vec<String> {
    help.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .collect()
}

/// Whether a help text lists `flag` (`--name` or `-x`) as an option.
fn lists_flag(help: &str, flag: &str) -> bool {
    help.lines().any(|l| {
        let l = l.trim_start();
        l.starts_with('-') && l.split([' ', ',', '=', '<', '[']).any(|w| w == flag)
    })
}

/// What is wrong with one shown command, if anything.
fn check(helps: &mut Helps, words: &[String]) -> Option<String> {
    let mut path: Vec<String> = Vec::new();
    let mut positional = false;
    for w in words {
        let w = w.trim_matches(|c| matches!(c, '[' | ']' | '(' | ')' | '"' | '\''));
        if w.is_empty() || w == "--" || w.starts_with('…') || w.starts_with("...") {
            continue;
        }
        if path.first().is_some_and(|p| p == "help") {
            return None;
        }
        if w.starts_with('-') && w.len() > 1 && !w[1..].starts_with(|c: char| c.is_ascii_digit()) {
            let flag = w.split('=').next().unwrap_or(w);
            // A short flag with its value attached (`-n5`) is not shown in these docs.
            if !lists_flag(helps.of(&path), flag) {
                return Some(format!("`prf {}` has no option {flag}", path.join(" ")));
            }
            positional = true;
            continue;
        }
        let help = helps.of(&path).to_string();
        let subs = subcommands(&help);
        if !positional && subs.iter().any(|s| s == w) {
            path.push(w.to_string());
            continue;
        }
        if !positional && !subs.is_empty() && !help.contains("\nArguments:") {
            // A subcommand's place, and no positional argument to take it.
            if !w.chars().next().is_some_and(|c| c.is_ascii_uppercase()) {
                return Some(format!("`prf {}` has no subcommand {w:?}", path.join(" ")));
            }
        }
        positional = true;
    }
    None
}

#[test]
fn every_prf_command_in_the_docs_names_existing_subcommands_and_flags() {
    let mut helps = Helps(HashMap::new());
    let (mut checked, mut wrong) = (0, Vec::new());
    for doc in documents() {
        for shown in commands_of(&doc) {
            checked += 1;
            if let Some(why) = check(&mut helps, &shown.words) {
                wrong.push(format!(
                    "{}: {why} (in `prf {}`)",
                    shown.at,
                    shown.words.join(" ")
                ));
            }
        }
    }
    assert!(checked > 50, "only {checked} commands found in the docs");
    assert!(
        wrong.is_empty(),
        "{} of {checked}:\n{}",
        wrong.len(),
        wrong.join("\n")
    );
}

#[test]
fn the_checker_finds_a_removed_flag_and_a_removed_subcommand() {
    let mut helps = Helps(HashMap::new());
    let words = |s: &str| s.split_whitespace().map(str::to_string).collect::<Vec<_>>();
    assert_eq!(
        check(&mut helps, &words("plan cell.blob --all --world w.json")),
        None
    );
    assert_eq!(
        check(&mut helps, &words("experiment monte-carlo --episodes 5")),
        None
    );
    assert_eq!(
        check(&mut helps, &words("envelope b --yaw-deg=-4,0,4 -o d")),
        None
    );
    assert!(check(&mut helps, &words("plan cell.blob --no-such-flag")).is_some());
    assert!(check(&mut helps, &words("experiment no-such-experiment")).is_some());
    assert!(check(&mut helps, &words("no-such-command")).is_some());
    let mut found = Vec::new();
    commands_in(
        "cargo run --release -p prf-offline --bin prf -- demo --task 1 | tail",
        "x",
        &mut found,
    );
    assert_eq!(found[0].words, ["demo", "--task", "1"]);
}
