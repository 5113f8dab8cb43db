//! The documentation holds together: the README stays short, every chapter of the book is in
//! its summary and every summary entry exists, and every local link of the README, ARCHITECTURE.md
//! and the book reaches a file; the scene reference is what the code prints.

use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The targets of the Markdown links `[text](target)` in `text` outside code blocks, without
/// web addresses and anchors within the page.
fn local_links(text: &str) -> Vec<String> {
    let mut links = Vec::new();
    let mut in_code = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
            continue;
        }
        if in_code {
            continue;
        }
        for part in line.split("](").skip(1) {
            let Some(end) = part.find(')') else { continue };
            let target = part[..end].split('#').next().unwrap_or_default();
            if !target.is_empty() && !target.contains("://") {
                links.push(target.to_owned());
            }
        }
    }
    links
}

fn chapters() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(root().join("docs/src"))
        .expect("docs/src")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    files.sort();
    files
}

#[test]
fn the_readme_is_a_short_tour() {
    let readme = std::fs::read_to_string(root().join("README.md")).expect("README.md");
    let lines = readme.lines().count();
    assert!(
        lines <= 200,
        "README.md has {lines} lines; the book holds the rest"
    );
    for command in ["./dev demo", "./dev test"] {
        assert!(readme.contains(command), "the set-up command {command}");
    }
}

#[test]
fn the_summary_lists_every_chapter_and_only_chapters_that_exist() {
    let summary = std::fs::read_to_string(root().join("docs/src/SUMMARY.md")).expect("SUMMARY.md");
    let listed = local_links(&summary);
    for chapter in chapters() {
        let name = chapter.file_name().unwrap().to_string_lossy().into_owned();
        if name != "SUMMARY.md" {
            assert!(listed.contains(&name), "{name} is not in SUMMARY.md");
        }
    }
    for entry in &listed {
        assert!(
            root().join("docs/src").join(entry).is_file(),
            "SUMMARY.md: {entry}"
        );
    }
}

#[test]
fn every_local_link_reaches_a_file() {
    let mut files = chapters();
    files.push(root().join("README.md"));
    files.push(root().join("ARCHITECTURE.md"));
    for file in files {
        let text = std::fs::read_to_string(&file).expect("a page");
        for link in local_links(&text) {
            let target = file.parent().unwrap().join(&link);
            assert!(
                target.exists(),
                "{}: link {link} leads nowhere",
                file.display()
            );
        }
    }
}

#[test]
fn the_scene_reference_is_what_the_code_prints() {
    let page = root().join("docs/src/scene-reference.md");
    let committed = std::fs::read_to_string(&page).expect("docs/src/scene-reference.md");
    assert!(
        committed == eddy::scene::reference::markdown(),
        "docs/src/scene-reference.md differs from what the code prints; regenerate it with \
         `cargo run --release -- scene-keys --markdown > docs/src/scene-reference.md`"
    );
}

/// The repository stands alone: no tracked text file names a path outside it (the design and
/// the papers' corrections the code relies on are in ARCHITECTURE.md and the book).
#[test]
fn no_file_cites_a_path_outside_the_repository() {
    let listed = std::process::Command::new("git")
        .args(["ls-files"])
        .current_dir(root())
        .output();
    let Some(listed) = listed.ok().filter(|o| o.status.success()) else {
        eprintln!("not a git checkout: the check is skipped");
        return;
    };
    // The folder beside the repository that held the design and the papers' errata, and their
    // file names; joined here so that this file names none of them itself.
    let outside = [
        ["..", "shared"].join("/"),
        ["shared", "DESIGN"].join("/"),
        ["PAPER", "NOTES"].join("-"),
    ];
    let mut found = Vec::new();
    for file in String::from_utf8_lossy(&listed.stdout).lines() {
        let Ok(text) = std::fs::read_to_string(root().join(file)) else {
            continue;
        };
        for (n, line) in text.lines().enumerate() {
            if outside.iter().any(|o| line.contains(o.as_str())) {
                found.push(format!("{file}:{}: {line}", n + 1));
            }
        }
    }
    assert!(found.is_empty(), "{}", found.join("\n"));
}
