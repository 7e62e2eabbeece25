//! `REPORT.html` in a real browser: merges the synthetic shards of the report tests
//! (`tests/report/fixtures/synthetic/`: a peer backend whose image differs from the
//! reference's, with its id and FLIP maps, and noisy timings) with the `raybench` binary,
//! loads the page from the file in headless Chromium (through the DevTools protocol,
//! `cdp.rs`), and drives it like a user, with real key presses and mouse clicks: the table
//! of contents, an image viewer (backends, layers, zoom, pixel-exact on a screenshot) and
//! the sortable tables, checking the DOM after every step and that the page reported no
//! error. A screenshot of the viewer is written to `target/tmp/report-viewer.png`.
//!
//! Without Chromium (`/usr/bin/chromium`, Debian's `chromium`, or `RAYBENCH_CHROMIUM`) the
//! test prints `skipped: <reason>` and passes, except under `CI=true`, where it fails.

#[path = "browser/cdp.rs"]
mod cdp;

use cdp::{Chromium, LaunchError, Page};
use serde::Deserialize;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The viewer driven: `spheres` cast by `naive` (the reference), `bvh` and `packet`
/// (bit-identical) and `bvh-crate` (differing in a square of 64 pixels).
const SCENE: &str = "spheres";
const MODE: &str = "cast";
/// The backend whose image differs, and its maps' files.
const DIFFERING: &str = "bvh-crate";
const DIFFERING_IDS: &str = "images/spheres-cast-primary-bvh-crate-ids-diff.png";
const DIFFERING_FLIP: &str = "images/spheres-cast-primary-bvh-crate-flip.png";

/// Where the screenshot of the viewer goes.
const SCREENSHOT: &str = concat!(env!("CARGO_TARGET_TMPDIR"), "/report-viewer.png");

#[test]
fn report_page_works_in_chromium() {
    let mut browser = match Chromium::launch() {
        Ok(browser) => browser,
        Err(LaunchError::Absent(why)) => {
            assert!(
                std::env::var("CI").as_deref() != Ok("true"),
                "no browser under CI=true: {why}"
            );
            eprintln!("skipped: {why}");
            return;
        }
        Err(LaunchError::Broken(why)) => panic!("{why}"),
    };
    let dir = render_report();
    let html = dir.join("REPORT.html");
    assert!(html.is_file(), "{} was not written", html.display());
    let results = results(&dir);

    let mut page = browser.new_page();
    page.navigate(&file_url(&html));
    assert_no_errors(&mut page, "loading the page");
    check_images_loaded(&mut page);
    check_table_of_contents(&mut page);
    check_viewers(&mut page, &results);
    drive_viewer(&mut page, &results, SCENE, MODE);
    check_noisy_cells(&mut page);
    sort_tables(&mut page);
    assert_no_errors(&mut page, "driving the page");
}

/// Merges the synthetic shards into `target/tmp/browser-report` (left there for people to
/// open) and returns the directory.
fn render_report() -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("browser-report");
    let _ = std::fs::remove_dir_all(&dir);
    let shards = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/report/fixtures/synthetic");
    let out = Command::new(env!("CARGO_BIN_EXE_raybench"))
        .arg("merge")
        .args([shards.join("shard-1"), shards.join("shard-2")])
        .arg("--out")
        .arg(&dir)
        .output()
        .expect("raybench runs");
    assert!(
        out.status.success(),
        "raybench merge failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    dir
}

fn results(dir: &Path) -> Value {
    let text = std::fs::read_to_string(dir.join("results.json")).expect("results.json written");
    serde_json::from_str(&text).expect("results.json is JSON")
}

/// `file://` and the absolute path, with every byte outside the unreserved set escaped.
fn file_url(path: &Path) -> String {
    let path = path.canonicalize().expect("the page exists");
    let mut url = String::from("file://");
    for &b in path.to_str().expect("a UTF-8 path").as_bytes() {
        if b.is_ascii_alphanumeric() || b"/-._~".contains(&b) {
            url.push(b as char);
        } else {
            url.push_str(&format!("%{b:02X}"));
        }
    }
    url
}

fn assert_no_errors(page: &mut Page, while_doing: &str) {
    let errors = page.errors();
    assert!(
        errors.is_empty(),
        "the page reported errors while {while_doing}:\n{}",
        errors.join("\n")
    );
}

/// No image on the page is broken (loaded with no pixels); lazy ones still loading are
/// left alone (a failed load also shows up as a logged error).
fn check_images_loaded(page: &mut Page) {
    let broken = page.eval(
        "[...document.images].filter(i => i.complete && i.naturalWidth === 0)\
         .map(i => i.getAttribute('src'))",
    );
    assert_eq!(broken, json!([]), "broken images");
}

/// The table of contents links to headings that exist, opens with the verdict, and a
/// click on its last link scrolls there.
fn check_table_of_contents(page: &mut Page) {
    let links = page.eval(
        "[...document.querySelectorAll('nav#toc a[href^=\"#\"]')].map(a => [a.getAttribute('href'), \
         !!document.getElementById(decodeURIComponent(a.getAttribute('href').slice(1)))])",
    );
    let links = links.as_array().expect("an array");
    assert!(
        links.len() >= 3,
        "nav#toc has {} links to this page: {links:?}",
        links.len()
    );
    for link in links {
        assert_eq!(
            link[1],
            json!(true),
            "nav#toc links to a missing id: {link}"
        );
    }
    assert!(
        links.iter().any(|l| l[0] == "#verdict"),
        "nav#toc has no link to #verdict: {links:?}"
    );
    // The verdict opens the report: it comes before every viewer and table.
    let verdict_first = page.eval(
        "(() => { const v = document.getElementById('verdict'); if (!v) return 'no #verdict'; \
         const later = [...document.querySelectorAll('section.viewer, table')]\
           .filter(e => !v.contains(e) && !(v.compareDocumentPosition(e) & Node.DOCUMENT_POSITION_FOLLOWING)); \
         return later.length === 0 ? true : later.map(e => e.id || e.tagName); })()",
    );
    assert_eq!(verdict_first, json!(true), "elements before the verdict");

    let last = links.last().unwrap()[0].as_str().unwrap().to_string();
    let link = format!("document.querySelector('nav#toc a[href=\"{last}\"]')");
    page.click_element(&link, &format!("the table of contents' link {last}"));
    page.wait_until(
        &format!(
            "location.hash === {hash} && (() => {{ const r = document.getElementById({id})\
             .getBoundingClientRect(); return r.top >= -1 && r.top < innerHeight; }})()",
            hash = json!(last),
            id = json!(&last[1..]),
        ),
        &format!("scrolled to {last} after clicking its link"),
    );
}

/// A scene's name as the page's ids write it: alphanumerics, `-` and `.` kept, others `_`.
fn file_safe(scene: &str) -> String {
    scene
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The primary-ray runs of one scene and mode that produced an image: (backend, reference,
/// identical to the reference).
fn image_runs(results: &Value, scene: &str, mode: &str) -> Vec<(String, String, bool)> {
    results["runs"]
        .as_array()
        .expect("runs")
        .iter()
        .filter(|r| {
            r["scene"] == scene
                && r["mode"] == mode
                && r["ray_set"] == "primary"
                && r["status"] == "ok"
        })
        .map(|r| {
            (
                r["backend"].as_str().unwrap().to_string(),
                r["reference"].as_str().unwrap().to_string(),
                r["equality"]["identical"] == true,
            )
        })
        .collect()
}

/// Every scene and mode of the results has a viewer with a pick button per backend, the
/// reference first.
fn check_viewers(page: &mut Page, results: &Value) {
    let mut pairs: Vec<(String, String)> = results["runs"]
        .as_array()
        .expect("runs")
        .iter()
        .filter(|r| r["ray_set"] == "primary" && r["status"] == "ok")
        .map(|r| {
            (
                r["scene"].as_str().unwrap().to_string(),
                r["mode"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    pairs.sort();
    pairs.dedup();
    // spheres and cornell-box, cast each.
    assert_eq!(pairs.len(), 2, "scene and mode pairs: {pairs:?}");
    for (scene, mode) in pairs {
        let id = format!("viewer-{}-{mode}", file_safe(&scene));
        let viewer = page.eval(&format!(
            "(() => {{ const v = document.getElementById({id}); if (!v) return null; \
             return {{ scene: v.dataset.scene, mode: v.dataset.mode, tag: v.tagName, \
             cls: v.className, tabindex: v.getAttribute('tabindex'), \
             picks: [...v.querySelectorAll('button.viewer-pick')].map(b => [b.dataset.backend, \
               b.dataset.reference === 'true']), \
             layers: [...v.querySelectorAll('button.viewer-layer')].map(b => b.dataset.layer), \
             images: v.querySelectorAll('img.viewer-image').length, \
             stats: v.querySelectorAll('.viewer-stats').length }}; }})()",
            id = json!(id)
        ));
        assert!(!viewer.is_null(), "no viewer #{id}");
        assert_eq!(viewer["scene"], scene.as_str(), "#{id}: {viewer}");
        assert_eq!(viewer["mode"], mode.as_str(), "#{id}: {viewer}");
        assert_eq!(viewer["tag"], "SECTION", "#{id}: {viewer}");
        assert!(
            viewer["cls"]
                .as_str()
                .unwrap()
                .split(' ')
                .any(|c| c == "viewer"),
            "#{id}: {viewer}"
        );
        assert_eq!(viewer["tabindex"], "0", "#{id}: {viewer}");
        assert_eq!(viewer["layers"], json!(["image", "ids", "flip"]), "#{id}");
        assert_eq!(viewer["images"], 1, "#{id}: {viewer}");
        assert_eq!(viewer["stats"], 1, "#{id}: {viewer}");
        let runs = image_runs(results, &scene, &mode);
        let reference = &runs[0].1;
        let picks = viewer["picks"].as_array().unwrap();
        assert_eq!(
            picks.first(),
            Some(&json!([reference, true])),
            "#{id}: the reference {reference} is not the first pick: {picks:?}"
        );
        assert_eq!(
            picks.iter().filter(|p| p[1] == true).count(),
            1,
            "#{id}: one reference: {picks:?}"
        );
        let mut shown: Vec<&str> = picks.iter().map(|p| p[0].as_str().unwrap()).collect();
        let mut ran: Vec<&str> = runs.iter().map(|r| r.0.as_str()).collect();
        shown.sort_unstable();
        ran.sort_unstable();
        assert_eq!(shown, ran, "#{id}: the picks are not the backends that ran");
    }
}

/// What a viewer shows, read from its DOM.
#[derive(Debug, Deserialize)]
struct ViewerState {
    /// `data-backend` of the image.
    backend: String,
    /// `data-layer` of the image.
    layer: String,
    /// `data-zoom` of the image.
    zoom: Option<String>,
    /// `src` of the image.
    src: String,
    /// The image's width on screen, in CSS pixels.
    width: f64,
    /// `image-rendering` of the image.
    rendering: String,
    /// `data-backend` of every pick button with `aria-pressed="true"`.
    pressed: Vec<String>,
    /// `data-backend` of the stats.
    stats_backend: Option<String>,
    /// The stats' text.
    stats: String,
    /// `data-derived` of the image: the layer drawn from the reference image because no
    /// map was stored (a result identical to the reference).
    derived: Option<String>,
}

/// Drives the viewer of `scene` and `mode` with keys and clicks, checking after each step
/// which backend, layer and zoom it shows; ends with a screenshot.
fn drive_viewer(page: &mut Page, results: &Value, scene: &str, mode: &str) {
    let id = format!("viewer-{}-{mode}", file_safe(scene));
    let sel = format!("#{id}");
    let runs = image_runs(results, scene, mode);
    let picks: Vec<String> = page
        .eval(&format!(
            "[...document.querySelectorAll('{sel} button.viewer-pick')].map(b => b.dataset.backend)"
        ))
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b.as_str().unwrap().to_string())
        .collect();
    assert!(picks.len() >= 3, "{sel}: {picks:?}");
    let identical = |backend: &str| runs.iter().any(|r| r.0 == backend && r.2);
    let differing = picks
        .iter()
        .position(|b| b == DIFFERING)
        .unwrap_or_else(|| panic!("{sel}: no pick {DIFFERING}: {picks:?}"));
    assert!(!identical(DIFFERING), "{sel}: {DIFFERING} is identical");

    // Focus the viewer as a user does: click its image (the section is focusable).
    let focus = |page: &mut Page| {
        page.click(&format!("{sel} img.viewer-image"));
        assert_eq!(
            page.eval(&format!(
                "document.activeElement === document.querySelector('{sel}')"
            )),
            json!(true),
            "clicking the image of {sel} did not focus the viewer"
        );
    };
    focus(page);
    let start = state(page, &sel);
    let zoom0: u32 = start
        .zoom
        .as_deref()
        .and_then(|z| z.parse().ok())
        .unwrap_or_else(|| panic!("{sel}: the image's data-zoom is {:?}", start.zoom));

    let mut expect = Expect {
        pick: 0,
        layer: "image",
        zoom: zoom0,
    };
    let step = |page: &mut Page, what: &str, expect: &Expect| -> ViewerState {
        let s = state(page, &sel);
        let backend = &picks[expect.pick];
        let zoom = expect.zoom.to_string();
        let context = format!("{sel} after {what}: {s:?}");
        assert_eq!(&s.backend, backend, "{context}");
        assert_eq!(s.layer, expect.layer, "{context}");
        assert_eq!(s.zoom.as_deref(), Some(zoom.as_str()), "{context}");
        assert_eq!(s.pressed, std::slice::from_ref(backend), "{context}");
        assert_eq!(
            s.stats_backend.as_deref(),
            Some(backend.as_str()),
            "{context}"
        );
        assert!(!s.src.is_empty(), "{context}");
        if expect.pick > 0 && identical(backend) {
            assert!(
                s.stats.to_lowercase().contains("identical"),
                "{context}: the stats of a bit-identical backend do not say so"
            );
        }
        if expect.pick == differing {
            // 4,032 of 4,096 ids, the PSNR and FLIP of its image; it fails the tolerance.
            for figure in ["FAILS", "98.4375 %", "28.4 dB", "0.0211"] {
                assert!(
                    s.stats.contains(figure),
                    "{context}: no {figure} in the stats"
                );
            }
        }
        s
    };

    let keys: [(&str, usize); 9] = [
        ("1", 0),
        ("ArrowRight", 1),
        ("ArrowRight", 2),
        ("ArrowLeft", 1),
        ("j", 2),
        ("k", 1),
        ("r", 0),
        ("3", 2),
        ("2", 1),
    ];
    page.press("i");
    let reference = step(page, "i", &expect);
    for (key, pick) in keys {
        page.press(key);
        expect.pick = pick;
        let s = step(page, &format!("key {key}"), &expect);
        if pick == 0 {
            assert_eq!(s.src, reference.src, "{sel}: the reference's image changed");
        }
    }
    // A click on a pick button selects that backend.
    let last = picks.len() - 1;
    page.click(&format!(
        "{sel} button.viewer-pick:nth-of-type({})",
        last + 1
    ));
    expect.pick = last;
    step(page, "clicking the last pick button", &expect);
    page.click(&format!(
        "{sel} button.viewer-pick[data-reference=\"true\"]"
    ));
    expect.pick = 0;
    step(page, "clicking the reference's pick button", &expect);

    focus(page);
    page.press("2");
    expect.pick = 1;
    let same = step(page, "key 2", &expect);
    assert!(identical(&picks[1]), "{sel}: {} differs", picks[1]);
    // A bit-identical backend's maps are derived from the reference image: none is stored.
    for (key, layer) in [("d", "ids"), ("f", "flip"), ("i", "image")] {
        page.press(key);
        expect.layer = layer;
        let s = step(page, &format!("key {key}"), &expect);
        let derived = (layer != "image").then(|| layer.to_string());
        assert_eq!(s.derived, derived, "{sel}: {s:?}");
        assert_eq!(s.src, same.src, "{sel}: {s:?}");
    }
    // The differing backend shows its own image and its stored maps, each a file of its own.
    page.press(&(differing + 1).to_string());
    expect.pick = differing;
    let own = step(page, "its pick key", &expect);
    assert_ne!(
        own.src, reference.src,
        "{sel}: {DIFFERING} shows the reference's image"
    );
    for (key, layer, file) in [
        ("d", "ids", DIFFERING_IDS),
        ("f", "flip", DIFFERING_FLIP),
        ("i", "image", own.src.as_str()),
    ] {
        page.press(key);
        expect.layer = layer;
        let s = step(page, &format!("key {key} on {DIFFERING}"), &expect);
        assert_eq!(
            (s.src.as_str(), s.derived.as_deref()),
            (file, None),
            "{sel}: {s:?}"
        );
    }
    // Zoom doubles the image's size on screen (pixel-exact) and halves it back.
    let base = state(page, &sel).width;
    for (key, factor) in [("+", 2), ("+", 4), ("-", 2)] {
        page.press(key);
        expect.zoom = zoom0 * factor;
        let s = step(page, &format!("key {key}"), &expect);
        assert!(
            (s.width - base * f64::from(factor)).abs() < 0.5,
            "{sel}: {factor} times zoom shows the image {} px wide, {base} px at the start",
            s.width
        );
        if factor == 2 {
            // Larger zooms may not fit the viewer's scrolled canvas, and a screenshot shows
            // only what is on screen.
            pixel_exact(page, &sel, zoom0 * factor, &s);
        }
    }

    let png = page.screenshot(&sel);
    assert!(png.starts_with(b"\x89PNG"), "the screenshot is not a PNG");
    std::fs::write(SCREENSHOT, &png).expect("the screenshot is written");
    eprintln!("screenshot of {sel}: {SCREENSHOT}");

    page.press("-");
    expect.zoom = zoom0;
    step(page, "key -", &expect);
}

/// Checks on a screenshot that the viewer's image at `zoom` shows every pixel of the file as
/// a `zoom` x `zoom` square of one colour (no smoothing, no offset).
fn pixel_exact(page: &mut Page, sel: &str, zoom: u32, s: &ViewerState) {
    let img = format!("{sel} img.viewer-image");
    let size = page.eval(&format!(
        "(() => {{ const i = document.querySelector('{img}'); return [i.naturalWidth, i.naturalHeight]; }})()"
    ));
    let (w, h) = (size[0].as_u64().unwrap(), size[1].as_u64().unwrap());
    let png = page.screenshot(&img);
    let shot = image::load_from_memory(&png)
        .expect("the screenshot decodes")
        .to_rgba8();
    let zoom = u64::from(zoom);
    assert_eq!(
        (u64::from(shot.width()), u64::from(shot.height())),
        (w * zoom, h * zoom),
        "{sel}: the image at zoom {zoom} on screen against its file of {w} x {h}"
    );
    let mut colours = std::collections::HashSet::new();
    for (x, y, p) in shot.enumerate_pixels() {
        let corner = shot.get_pixel(x - x % zoom as u32, y - y % zoom as u32);
        assert_eq!(
            p, corner,
            "{sel}: at zoom {zoom} the screen pixel ({x}, {y}) differs from the top left of its \
             square: the image is smoothed or shifted, not pixel-exact (image-rendering is {}; \
             {s:?})",
            s.rendering
        );
        colours.insert(p.0);
    }
    // A flat image would prove nothing.
    assert!(
        colours.len() > 8,
        "{sel}: the image has {} colours",
        colours.len()
    );
}

/// What the viewer should show.
struct Expect {
    /// The index of the backend among the pick buttons.
    pick: usize,
    layer: &'static str,
    zoom: u32,
}

/// Reads what the viewer `sel` shows, once its image has loaded.
fn state(page: &mut Page, sel: &str) -> ViewerState {
    let img = format!("document.querySelector('{sel} img.viewer-image')");
    page.wait_until(
        &format!("{img}.complete && {img}.naturalWidth > 0"),
        &format!("the image of {sel} loaded"),
    );
    let value = page.eval(&format!(
        "(() => {{ const v = document.querySelector('{sel}'); const img = {img}; \
         const stats = v.querySelector('.viewer-stats'); \
         return {{ backend: img.dataset.backend ?? '', layer: img.dataset.layer ?? '', \
           zoom: img.dataset.zoom ?? null, src: img.getAttribute('src') ?? '', \
           width: img.getBoundingClientRect().width, \
           rendering: getComputedStyle(img).imageRendering, \
           pressed: [...v.querySelectorAll('button.viewer-pick[aria-pressed=\"true\"]')]\
             .map(b => b.dataset.backend), \
           stats_backend: stats.dataset.backend ?? null, stats: stats.textContent, \
           derived: img.dataset.derived ?? null }}; }})()"
    ));
    serde_json::from_value(value.clone())
        .unwrap_or_else(|e| panic!("{sel}: unexpected state {value}: {e}"))
}

/// Every cell that flags a noisy figure (`†`) has class `noisy`, and no other; the page has
/// the six the synthetic shards make (the verdict's Cornell box cell, the summary's two
/// Cornell box figures, the three noisy times of the per-scene tables).
fn check_noisy_cells(page: &mut Page) {
    let noisy = page
        .eval("[...document.querySelectorAll('table.sortable td.noisy')].map(c => c.textContent)");
    let noisy: Vec<&str> = noisy
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_str().unwrap())
        .collect();
    assert_eq!(noisy.len(), 6, "noisy cells: {noisy:?}");
    for text in [
        "3.90 †",
        "1.95 †",
        "0.00300 [0.00240-0.00360] †",
        "0.00210 [0.00180-0.00250] †",
        "0.00105 [0.000900-0.00130] †",
    ] {
        assert!(noisy.contains(&text), "no noisy cell {text:?}: {noisy:?}");
    }
    assert!(
        noisy.iter().any(|c| c.starts_with("packet 3.90 †")),
        "the verdict's noisy cell: {noisy:?}"
    );
    let wrong = page.eval(
        "[...document.querySelectorAll('table.sortable td')]\
         .filter(c => c.textContent.includes('\u{2020}') !== c.classList.contains('noisy'))\
         .map(c => c.outerHTML)",
    );
    assert_eq!(
        wrong,
        json!([]),
        "cells whose class noisy disagrees with their mark"
    );
    let plain = page.eval(
        "[...document.querySelectorAll('table:not(.sortable)')].map(t => t.outerHTML.slice(0, 200))",
    );
    assert_eq!(plain, json!([]), "tables that do not sort");
}

/// The number a cell shows, in the unit the page sorts by: its first number, thousands
/// separators and marks (`†`) ignored, scaled by a unit of time or size right after it
/// (`ms`, `KiB`), `inf` as infinity; `None` for a missing figure (`-`, empty), `Err` for
/// text without a number.
fn cell_number(text: &str) -> Result<Option<f64>, ()> {
    let text: String = text.chars().filter(|&c| c != ',').collect();
    let t = text.trim();
    if t.is_empty() || t == "-" || t == "\u{2013}" || t == "\u{2014}" {
        return Ok(None);
    }
    if t.get(..3).is_some_and(|s| s.eq_ignore_ascii_case("inf")) {
        return Ok(Some(f64::INFINITY));
    }
    let b = t.as_bytes();
    let start = (0..b.len())
        .find(|&i| {
            b[i].is_ascii_digit() || (b[i] == b'-' && b.get(i + 1).is_some_and(u8::is_ascii_digit))
        })
        .ok_or(())?;
    // The longest prefix of the run of number characters that parses (`12.5e3`, not `12.5e`).
    let run = b[start + 1..]
        .iter()
        .take_while(|c| c.is_ascii_digit() || b".eE+-".contains(c))
        .count();
    let (end, number) = (start + 1..=start + 1 + run)
        .rev()
        .find_map(|end| Some((end, t[start..end].parse::<f64>().ok()?)))
        .ok_or(())?;
    let unit: String = t[end..]
        .trim_start()
        .chars()
        .take_while(|&c| c.is_alphabetic() || c == '%')
        .collect();
    let scale = match unit.as_str() {
        "ns" => 1e-9,
        "\u{b5}s" | "us" => 1e-6,
        "ms" => 1e-3,
        "KiB" => 1024.0,
        "MiB" => 1024.0 * 1024.0,
        "GiB" => 1024.0 * 1024.0 * 1024.0,
        _ => 1.0,
    };
    Ok(Some(number * scale))
}

/// The numbers of column `col`, or `None` when a cell is not a number.
fn column(rows: &[Vec<String>], col: usize) -> Option<Vec<Option<f64>>> {
    rows.iter().map(|r| cell_number(r.get(col)?).ok()).collect()
}

/// The header and body rows of every sortable table, as text.
fn tables(page: &mut Page) -> Vec<(Vec<String>, Vec<Vec<String>>)> {
    let value = page.eval(
        "[...document.querySelectorAll('table.sortable')].map(t => { \
           const rows = [...t.rows].map(r => [...r.cells].map(c => c.textContent.trim())); \
           return [rows[0] ?? [], rows.slice(1)]; })",
    );
    serde_json::from_value(value).expect("tables as text")
}

/// In the first sortable table of each kind (by its header) with at least three rows, clicks
/// the header of every numeric column with two different values twice, and checks the order
/// and `aria-sort` after each click (one of the two clicks must move rows).
fn sort_tables(page: &mut Page) {
    let all = tables(page);
    assert!(!all.is_empty(), "no table.sortable on the page");
    let mut kinds = Vec::new();
    for (t, (head, rows)) in all.iter().enumerate() {
        if rows.len() < 3 || kinds.contains(&head) {
            continue;
        }
        kinds.push(head);
        let numeric: Vec<usize> = (0..head.len())
            .filter(|&col| {
                column(rows, col).is_some_and(|numbers| {
                    let known: Vec<f64> = numbers.iter().flatten().copied().collect();
                    known.iter().any(|&x| x != known[0])
                })
            })
            .collect();
        sort_columns(page, &all, t, &numeric);
    }
    assert!(!kinds.is_empty(), "no sortable table has three rows");
}

/// Sorts table `t` by each of `columns` (see [`sort_tables`]).
fn sort_columns(
    page: &mut Page,
    all: &[(Vec<String>, Vec<Vec<String>>)],
    t: usize,
    columns: &[usize],
) {
    for &col in columns {
        let th = format!("document.querySelectorAll('table.sortable')[{t}].rows[0].cells[{col}]");
        let name = format!("table {t}'s column {col} ({})", all[t].0[col]);
        let mut before = all[t].1.clone();
        before.sort();
        for (click, order) in [(1, "ascending"), (2, "descending")] {
            page.click_element(&th, &name);
            let aria = page.eval(&format!("{th}.getAttribute('aria-sort')"));
            assert_eq!(aria, order, "{name}: aria-sort after click {click}");
            let rows = tables(page)[t].1.clone();
            let numbers = column(&rows, col).expect("the same numbers");
            let sorted = if order == "ascending" {
                ascending(&numbers)
            } else {
                let negated: Vec<Option<f64>> = numbers.iter().map(|n| n.map(|x| -x)).collect();
                ascending(&negated)
            };
            assert!(
                sorted,
                "{name} is not {order} (missing figures last) after click {click}: {:?}",
                rows.iter().map(|r| r[col].as_str()).collect::<Vec<_>>()
            );
            let mut after = rows;
            after.sort();
            assert_eq!(after, before, "{name}: sorting changed the rows");
        }
    }
}

/// Whether the numbers are in ascending order with the missing ones last.
fn ascending(numbers: &[Option<f64>]) -> bool {
    let known = numbers.iter().take_while(|n| n.is_some()).count();
    numbers[known..].iter().all(Option::is_none)
        && numbers[..known].windows(2).all(|w| w[0] <= w[1])
}
