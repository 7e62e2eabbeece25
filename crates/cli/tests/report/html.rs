//! `REPORT.html`, as `report` and `merge` write it: what the page is made of (the browser
//! test, `tests/browser.rs`, drives it).

use crate::common::{assert_success, merge, read};
use crate::{markdown, small_report, tmp_dir};

/// The attribute values `name="..."` of an HTML text.
fn attributes<'a>(html: &'a str, name: &str) -> Vec<&'a str> {
    let key = format!(" {name}=\"");
    html.match_indices(&key)
        .map(|(i, _)| {
            let rest = &html[i + key.len()..];
            &rest[..rest.find('"').unwrap()]
        })
        .collect()
}

/// `REPORT.html` (written by `report` and by `merge`): one page opening with the verdict and
/// a table of contents, every Markdown table sortable, one viewer per scene and mode with
/// frames, and every file it shows beside it (relative paths, nothing from the network).
/// The browser test (`tests/browser.rs`) drives the page; this checks what it is made of.
#[test]
fn report_html_is_one_page_with_viewers_and_local_files() {
    let (dir, merged) = (tmp_dir("html"), tmp_dir("html-merged"));
    small_report(&dir, &[]);
    assert_success(&merge(&[&dir], &merged));
    for d in [&dir, &merged] {
        let html = read(d, "REPORT.html");
        let md = markdown(d);
        assert!(html.starts_with("<!DOCTYPE html>"), "{html}");
        assert!(html.contains("<nav id=\"toc\""));
        // The verdict first: before the shards' machines and the reading guide.
        let at = |needle: &str| html.find(needle).unwrap_or_else(|| panic!("{needle}"));
        assert!(at("<h2 id=\"verdict\">") < at("<details class=\"machines\">"));
        assert!(at("<details class=\"machines\">") < at("<h2 id=\"how-to-read-this-report\">"));
        for id in attributes(&html, "href")
            .into_iter()
            .filter(|h| h.starts_with('#'))
        {
            assert!(
                html.contains(&format!("id=\"{}\"", &id[1..])),
                "a link to {id} without its target"
            );
        }
        // Every Markdown table, sortable.
        let tables = md.lines().filter(|l| l.starts_with("|---")).count();
        assert!(tables > 5);
        assert_eq!(html.matches("<table class=\"sortable\">").count(), tables);
        // One viewer per scene and mode with frames: spheres cast and whitted, the Cornell
        // box cast, whitted and path; naive the reference, then bvh and packet.
        assert!(
            !html.contains("raybench-viewer"),
            "a marker left in the page"
        );
        let viewers = attributes(&html, "id")
            .into_iter()
            .filter(|i| i.starts_with("viewer-"))
            .collect::<Vec<_>>();
        assert_eq!(
            viewers,
            [
                "viewer-spheres-cast",
                "viewer-spheres-whitted",
                "viewer-cornell-box-cast",
                "viewer-cornell-box-whitted",
                "viewer-cornell-box-path"
            ]
        );
        let picks: Vec<&str> = attributes(&html, "data-backend");
        assert!(
            picks.windows(3).any(|w| w == ["naive", "bvh", "packet"]),
            "{picks:?}"
        );
        assert_eq!(html.matches("data-reference=\"true\"").count(), 5);
        // Files beside the page, by relative paths that exist; no network.
        let mut files = attributes(&html, "src");
        // The charts, embedded as objects.
        files.extend(attributes(&html, "data"));
        for a in ["data-image", "data-ids", "data-flip"] {
            files.extend(attributes(&html, a).into_iter().filter(|f| !f.is_empty()));
        }
        assert!(files.len() >= 5);
        for f in files {
            assert!(!f.contains("//") && !f.starts_with('/'), "{f}");
            assert!(d.join(f).is_file(), "{f} is not beside the page");
        }
        // No address but the SVG namespace: nothing is fetched.
        let without_namespaces = html
            .replace("http://www.w3.org/2000/svg", "")
            .replace("http://www.w3.org/1999/xlink", "");
        assert!(
            !without_namespaces.contains("http"),
            "an address in the page"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&merged);
}
