//! The documentation holds together: the README stays short, every chapter of the book is in
//! its summary and every summary entry exists, every link and image of the README,
//! ARCHITECTURE.md and the book reaches a file of the repository (the book's inside its `src/`,
//! the only folder mdBook renders) and every `#anchor` a heading; the scene reference is what the
//! code prints.

use std::collections::HashSet;
use std::path::{Component, Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// `line` without its code spans (`` `a](b)` `` is no link).
fn without_code_spans(line: &str) -> String {
    let mut out = String::new();
    let mut rest = line;
    while let Some(start) = rest.find('`') {
        out.push_str(&rest[..start]);
        let ticks = rest[start..].len() - rest[start..].trim_start_matches('`').len();
        let fence = &rest[start..start + ticks];
        let after = &rest[start + ticks..];
        match after.find(fence) {
            Some(end) => rest = &after[end + ticks..],
            None => {
                out.push_str(&rest[start..]);
                return out;
            }
        }
    }
    out.push_str(rest);
    out
}

/// The lines of a Markdown page outside fenced code blocks, numbered from 1.
fn prose(text: &str) -> Vec<(usize, &str)> {
    let mut lines = Vec::new();
    let mut in_code = false;
    for (n, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
        } else if !in_code {
            lines.push((n + 1, line));
        }
    }
    lines
}

/// The targets of the links and images `[text](target)`, `![alt](target "title")` of a page,
/// with their line numbers, leaving out web addresses (`scheme://`, `mailto:`).
fn links(text: &str) -> Vec<(usize, String)> {
    let mut found = Vec::new();
    for (n, line) in prose(text) {
        for part in without_code_spans(line).split("](").skip(1) {
            let target = match part.strip_prefix('<') {
                Some(inside) => inside.split('>').next(),
                None => part.split([')', ' ']).next(),
            };
            let target = target.unwrap_or_default().trim();
            if !target.is_empty() && !target.contains("://") && !target.starts_with("mailto:") {
                found.push((n, target.to_owned()));
            }
        }
    }
    found
}

/// The anchors of a page's headings as mdBook makes them: the heading's text lower-cased, its
/// letters, digits, `_` and `-` kept, spaces turned to `-`, the rest dropped; a repeated one
/// gets `-1`, `-2`, ...
fn anchors(text: &str) -> HashSet<String> {
    let mut ids = HashSet::new();
    for (_, line) in prose(text) {
        let hashes = line.len() - line.trim_start_matches('#').len();
        if !(1..=6).contains(&hashes) || !line[hashes..].starts_with(' ') {
            continue;
        }
        // The heading's text: code without its backticks, a link's text without its target.
        let unquoted = line[hashes..].trim().replace('`', "");
        let mut rest = unquoted.as_str();
        let mut heading = String::new();
        while let Some(start) = rest.find("](") {
            heading.push_str(&rest[..start]);
            rest = rest[start..].split_once(')').map_or("", |(_, r)| r);
        }
        heading.push_str(rest);
        let id: String = heading
            .trim()
            .to_lowercase()
            .chars()
            .filter_map(|c| match c {
                c if c.is_alphanumeric() || c == '_' || c == '-' => Some(c),
                c if c.is_whitespace() => Some('-'),
                _ => None,
            })
            .collect();
        let mut unique = id.clone();
        let mut k = 0;
        while !ids.insert(unique.clone()) {
            k += 1;
            unique = format!("{id}-{k}");
        }
    }
    ids
}

/// `path` with its `.` and `..` resolved without touching the file system (a `..` above the
/// start is kept).
fn normalise(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for part in path.components() {
        match part {
            Component::CurDir => {}
            Component::ParentDir if out.file_name().is_some() => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}

/// The files of the repository, relative to its root: tracked or new but not ignored (a link
/// into `target/` or `out/` reaches nothing on a fresh checkout); `None` outside a git checkout.
fn repository_files() -> Option<HashSet<PathBuf>> {
    let listed = std::process::Command::new("git")
        .args([
            "ls-files",
            "-z",
            "--cached",
            "--others",
            "--exclude-standard",
        ])
        .current_dir(root())
        .output()
        .ok()
        .filter(|o| o.status.success())?;
    Some(
        String::from_utf8_lossy(&listed.stdout)
            .split('\0')
            .filter(|f| !f.is_empty())
            .map(PathBuf::from)
            .collect(),
    )
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

/// What is wrong with each link of `page` (its path from the root, and its text): a target must
/// be a file or folder of the repository, for a book page a file inside `docs/src` and, if a
/// page, a chapter of the summary; an anchor (`page.md#anchor`, `#anchor`) must be a heading of
/// its page.
fn broken_links(page: &Path, text: &str, repository: Option<&HashSet<PathBuf>>) -> Vec<String> {
    let book = Path::new("docs/src");
    let in_book = page.starts_with(book);
    let summary = std::fs::read_to_string(root().join("docs/src/SUMMARY.md")).expect("SUMMARY.md");
    let chapters: Vec<PathBuf> = links(&summary)
        .into_iter()
        .map(|(_, l)| book.join(l))
        .collect();
    let mut broken = Vec::new();
    for (line, link) in links(text) {
        let (path, anchor) = link.split_once('#').unwrap_or((&link, ""));
        let target = normalise(&page.parent().unwrap().join(path));
        let is_page = target.extension().is_some_and(|e| e == "md");
        let known = repository.is_none_or(|files| files.iter().any(|f| f.starts_with(&target)));
        let wrong = if path.is_empty() {
            None
        } else if target.starts_with("..") || !root().join(&target).exists() || !known {
            Some("no file of the repository")
        } else if in_book && !(target.starts_with(book) && root().join(&target).is_file()) {
            Some("outside docs/src, which mdBook does not copy")
        } else if in_book && is_page && !chapters.contains(&target) {
            Some("a page that is not in SUMMARY.md, which mdBook does not render")
        } else {
            None
        };
        let wrong = wrong.or_else(|| {
            let heads = match path {
                "" => text.to_owned(),
                _ if !is_page || anchor.is_empty() => return None,
                _ => std::fs::read_to_string(root().join(&target)).expect("the linked page"),
            };
            (!anchors(&heads).contains(anchor)).then_some("no heading with this anchor")
        });
        if let Some(wrong) = wrong {
            broken.push(format!("{}:{line}: {link}: {wrong}", page.display()));
        }
    }
    broken
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
    let listed: Vec<String> = links(&summary).into_iter().map(|(_, l)| l).collect();
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
fn every_link_and_image_reaches_a_file_of_the_repository() {
    let repository = repository_files();
    let mut pages = vec![PathBuf::from("README.md"), PathBuf::from("ARCHITECTURE.md")];
    pages.extend(
        chapters()
            .iter()
            .map(|c| c.strip_prefix(root()).unwrap().to_path_buf()),
    );
    let mut broken = Vec::new();
    for page in &pages {
        let text = std::fs::read_to_string(root().join(page)).expect("a page");
        broken.extend(broken_links(page, &text, repository.as_ref()));
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

/// The check above finds each kind of broken link, and passes the kinds that work.
#[test]
fn the_link_check_finds_broken_links() {
    let page = Path::new("docs/src/a-new-chapter.md");
    let bad = [
        "![a figure beside the book](../figures/slice.png)",
        "[a chapter that is not there](no-such-chapter.md)",
        "[a page mdBook does not render](../../ARCHITECTURE.md)",
        "[a heading that is not there](outputs.md#no-such-heading)",
        "[an anchor of this page](#no-such-heading)",
        "[out of the repository](../../../elsewhere.md)",
        "[a folder outside the book](../../scenes)",
    ];
    for link in bad {
        let found = broken_links(page, &format!("# A chapter\n\nSee {link}.\n"), None);
        assert_eq!(found.len(), 1, "{link}: {found:?}");
    }
    let good = "# A chapter\n\n![a figure](figures/slice_sphere_wake.png) [Outputs](outputs.md), \
                [its statistics](outputs.md#statistics), [this heading](#a-chapter), \
                [the web](https://example.org/x.md), `[code](nowhere.md)`\n\n```\n[code](nowhere.md)\n```\n";
    assert_eq!(broken_links(page, good, None), Vec::<String>::new());
    // Outside the book a folder is a target too, but not one git ignores or holds itself.
    if let Some(files) = repository_files() {
        let readme = "[the scenes](scenes) [the design](ARCHITECTURE.md) [git's folder](.git)";
        let found = broken_links(Path::new("README.md"), readme, Some(&files));
        assert_eq!(found.len(), 1, "{found:?}");
        assert!(found[0].contains(".git"), "{found:?}");
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
