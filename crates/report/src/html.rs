//! `REPORT.html`: the report as one page to look at in a browser, made from the text of
//! `REPORT.md` (so the two never disagree) and [`Results`].
//!
//! What the page adds to the Markdown: the verdict first and a table of contents beside
//! it; an image viewer per scene and mode in place of the thumbnails (the reference and
//! each backend's image at the same place, switched by keys or clicks as in the JERI and
//! tev viewers, with the id-difference and FLIP maps, their colour keys, pixel-exact zoom
//! and the figures of the current pair); tables that sort by any column, noisy figures
//! marked; charts embedded as SVG documents, so their points show tooltips. One file, no
//! network, no build step: images and charts are beside it (relative paths), its style and
//! script are inlined (`assets/report.css`, `assets/report.js`).
//!
//! The page's structure is a contract with its script and with the browser test
//! (`crates/cli/tests/browser.rs`): `nav#toc`; each viewer a `section.viewer` with
//! `button.viewer-pick[data-backend]` (the reference first, `data-reference="true"`),
//! `button.viewer-layer[data-layer=image|ids|flip]` (and `visits` where a backend has a
//! heat map of node visits per pixel), one `img.viewer-image` and one
//! `.viewer-stats`; every data table a `table.sortable`, its noisy cells `td.noisy`.

use crate::charts::escape as esc;
use crate::experiments::matrix::{self, VIEWER_BEGIN, VIEWER_END, WorkloadKey};
use crate::results::{Results, Run};
use pulldown_cmark::{Alignment, CowStr, Event, HeadingLevel, Options, Parser, Tag, TagEnd};
use std::fmt::Write as _;
use std::path::Path;

/// The page's style.
const CSS: &str = include_str!("assets/report.css");
/// The page's script: the viewers, table sorting, the table of contents' highlight.
const JS: &str = include_str!("assets/report.js");

/// The page of a report whose Markdown text is `markdown`, written into the folder `out`
/// (where its charts are looked for).
#[must_use]
pub fn page(results: &Results, markdown: &str, out: &Path) -> String {
    let (markdown, viewers) = take_viewers(markdown);
    let events: Vec<Event> = Parser::new_ext(&markdown, Options::ENABLE_TABLES).collect();
    let mut headings = Vec::new();
    let events = name_headings(events, &mut headings);
    let sections = split_sections(events);

    let title = headings
        .iter()
        .find(|h| h.level == HeadingLevel::H1)
        .map_or_else(|| "raybench report".to_string(), |h| h.text.clone());
    let mut body = String::new();
    // The verdict first, then the machines and commands (the Markdown's preamble), then the
    // rest in order.
    let (preamble, rest) = sections
        .split_first()
        .map_or((&[][..], &[][..]), |(p, r)| (p.as_slice(), r));
    let mut rest = rest.iter();
    if let Some(verdict) = rest.next() {
        render(verdict, out, &mut body);
    }
    let preamble: Vec<Event> = preamble
        .iter()
        .skip_while(|e| !matches!(e, Event::End(TagEnd::Heading(HeadingLevel::H1))))
        .skip(1)
        .cloned()
        .collect();
    if !preamble.is_empty() {
        body.push_str(
            "<details class=\"machines\"><summary>Machines, commands and durations of the \
             shards</summary>\n",
        );
        render(&preamble, out, &mut body);
        body.push_str("</details>\n");
    }
    for section in rest {
        render(section, out, &mut body);
    }
    // The viewers, in place of their placeholders.
    let keys = matrix::measured(results);
    for (index, placeholder) in viewers {
        let viewer = keys
            .get(index)
            .map(|k| viewer(results, k))
            .unwrap_or_default();
        body = body.replace(&placeholder, &viewer);
    }

    let mut s = String::new();
    let _ = write!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <meta name=\"generator\" content=\"raybench {}\">\n<title>{}</title>\n\
         <style>\n{CSS}</style>\n</head>\n<body>\n",
        env!("CARGO_PKG_VERSION"),
        esc(&title)
    );
    s.push_str(&toc(&headings));
    let _ = write!(
        s,
        "<main>\n<h1 id=\"top\">{}</h1>\n{}{body}</main>\n<script>\n{JS}</script>\n</body>\n</html>\n",
        esc(&title),
        subtitle(results)
    );
    s
}

/// A line under the title: the machines and when.
fn subtitle(results: &Results) -> String {
    let machines: Vec<String> = results
        .shards
        .iter()
        .map(|sh| {
            format!(
                "{} ({} threads), {}",
                sh.machine.cpu,
                sh.machine.threads,
                sh.started.get(..10).unwrap_or(&sh.started)
            )
        })
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    if machines.is_empty() {
        return String::new();
    }
    format!(
        "<p class=\"subtitle\">{} shard{} on {}</p>\n",
        results.shards.len(),
        if results.shards.len() == 1 { "" } else { "s" },
        esc(&machines.join("; "))
    )
}

/// Replaces each viewer's lines of the Markdown (between [`VIEWER_BEGIN`] and
/// [`VIEWER_END`]) with a placeholder block; returns the text and `(workload index,
/// placeholder)` for each.
fn take_viewers(markdown: &str) -> (String, Vec<(usize, String)>) {
    let mut text = String::with_capacity(markdown.len());
    let mut viewers = Vec::new();
    let mut rest = markdown;
    while let Some(start) = rest.find(VIEWER_BEGIN) {
        let after = &rest[start + VIEWER_BEGIN.len()..];
        let (Some(close), Some(end)) = (after.find("-->"), after.find(VIEWER_END)) else {
            break;
        };
        let Ok(index) = after[..close].trim().parse::<usize>() else {
            break;
        };
        text.push_str(&rest[..start]);
        let placeholder = format!("<div data-raybench-viewer=\"{index}\"></div>");
        let _ = write!(text, "{placeholder}\n\n");
        viewers.push((index, placeholder));
        rest = &after[end + VIEWER_END.len()..];
    }
    text.push_str(rest);
    (text, viewers)
}

/// A heading of the page: its level, text and `id`.
struct Heading {
    level: HeadingLevel,
    text: String,
    id: String,
}

/// Gives every heading an `id` (its text as a slug, made unique) and records them.
fn name_headings<'a>(events: Vec<Event<'a>>, headings: &mut Vec<Heading>) -> Vec<Event<'a>> {
    let mut out = Vec::with_capacity(events.len());
    let mut i = 0;
    while i < events.len() {
        if let Event::Start(Tag::Heading {
            level,
            classes,
            attrs,
            ..
        }) = &events[i]
        {
            let mut text = String::new();
            for e in events[i + 1..]
                .iter()
                .take_while(|e| !matches!(e, Event::End(TagEnd::Heading(_))))
            {
                if let Event::Text(t) | Event::Code(t) = e {
                    text.push_str(t);
                }
            }
            let base = slug(&text);
            let mut id = base.clone();
            let mut n = 2;
            while id == "top" || headings.iter().any(|h| h.id == id) {
                id = format!("{base}-{n}");
                n += 1;
            }
            out.push(Event::Start(Tag::Heading {
                level: *level,
                id: Some(CowStr::from(id.clone())),
                classes: classes.clone(),
                attrs: attrs.clone(),
            }));
            headings.push(Heading {
                level: *level,
                text,
                id,
            });
        } else {
            out.push(events[i].clone());
        }
        i += 1;
    }
    out
}

/// `text` in lower case, runs of other characters than letters and digits as one `-`.
fn slug(text: &str) -> String {
    let mut s = String::new();
    for c in text.chars().flat_map(char::to_lowercase) {
        if c.is_alphanumeric() {
            s.push(c);
        } else if !s.ends_with('-') && !s.is_empty() {
            s.push('-');
        }
    }
    let s = s.trim_end_matches('-').to_string();
    if s.is_empty() { "section".into() } else { s }
}

/// The events split before each second-level heading: the first part is what precedes the
/// first one.
fn split_sections(events: Vec<Event>) -> Vec<Vec<Event>> {
    let mut sections = vec![Vec::new()];
    for e in events {
        if matches!(
            e,
            Event::Start(Tag::Heading {
                level: HeadingLevel::H2,
                ..
            })
        ) {
            sections.push(Vec::new());
        }
        sections.last_mut().expect("one section at least").push(e);
    }
    sections
}

/// The table of contents: every second-level heading, its third-level ones under it.
fn toc(headings: &[Heading]) -> String {
    let mut s = String::from(
        "<nav id=\"toc\" aria-label=\"Contents\">\n<p class=\"toc-title\"><a href=\"#top\">Contents</a></p>\n<ul>\n",
    );
    let mut open_sub = false;
    for h in headings {
        match h.level {
            HeadingLevel::H2 => {
                if open_sub {
                    s.push_str("</ul>");
                    open_sub = false;
                }
                if !s.ends_with("<ul>\n") {
                    s.push_str("</li>\n");
                }
                let _ = write!(s, "<li><a href=\"#{}\">{}</a>", h.id, esc(&h.text));
            }
            HeadingLevel::H3 => {
                if !open_sub {
                    s.push_str("<ul>");
                    open_sub = true;
                }
                let _ = write!(s, "<li><a href=\"#{}\">{}</a></li>", h.id, esc(&h.text));
            }
            _ => {}
        }
    }
    if open_sub {
        s.push_str("</ul>");
    }
    if !s.ends_with("<ul>\n") {
        s.push_str("</li>\n");
    }
    s.push_str("</ul>\n</nav>\n");
    s
}

/// Renders `events` as HTML into `s`: tables sortable and their noisy cells marked, chart
/// images (`charts/*.svg`, when the file is in `out`) embedded as objects.
fn render(events: &[Event], out: &Path, s: &mut String) {
    let mut plain: Vec<Event> = Vec::new();
    let mut i = 0;
    while i < events.len() {
        match &events[i] {
            Event::Start(Tag::Table(align)) => {
                let end = find_end(events, i, |e| matches!(e, Event::End(TagEnd::Table)));
                pulldown_cmark::html::push_html(s, plain.drain(..));
                table(align, &events[i + 1..end], s);
                i = end + 1;
                continue;
            }
            Event::Start(Tag::Image { dest_url, .. })
                if dest_url.starts_with("charts/") && dest_url.ends_with(".svg") =>
            {
                let end = find_end(events, i, |e| matches!(e, Event::End(TagEnd::Image)));
                if out.join(dest_url.as_ref()).is_file() {
                    let title: String = events[i + 1..end]
                        .iter()
                        .filter_map(|e| match e {
                            Event::Text(t) => Some(t.as_ref()),
                            _ => None,
                        })
                        .collect();
                    // An object, not an img: the chart stays a live SVG document, so its
                    // points' titles show on hover; not inlined, so a full report's page
                    // stays small (its charts are about as large as the rest of it).
                    plain.push(Event::InlineHtml(CowStr::from(format!(
                        "<object class=\"chart\" type=\"image/svg+xml\" data=\"{}\" aria-label=\"{}\">{}</object>",
                        esc(dest_url),
                        esc(&title),
                        esc(&title)
                    ))));
                } else {
                    plain.extend(events[i..=end].iter().cloned());
                }
                i = end + 1;
                continue;
            }
            e => plain.push(e.clone()),
        }
        i += 1;
    }
    pulldown_cmark::html::push_html(s, plain.into_iter());
}

/// The index of the first event after `start` that `is_end` accepts (the last index when
/// none does).
fn find_end(events: &[Event], start: usize, is_end: impl Fn(&Event) -> bool) -> usize {
    events[start..]
        .iter()
        .position(is_end)
        .map_or(events.len() - 1, |p| start + p)
}

/// A Markdown table (the events between its start and end) as a sortable HTML table.
fn table(align: &[Alignment], events: &[Event], s: &mut String) {
    s.push_str("<div class=\"table-wrap\"><table class=\"sortable\">\n");
    let mut column = 0;
    let mut in_head = false;
    let mut i = 0;
    while i < events.len() {
        match &events[i] {
            Event::Start(Tag::TableHead) => {
                in_head = true;
                column = 0;
                s.push_str("<thead><tr>");
            }
            Event::End(TagEnd::TableHead) => {
                in_head = false;
                s.push_str("</tr></thead>\n<tbody>\n");
            }
            Event::Start(Tag::TableRow) => {
                column = 0;
                s.push_str("<tr>");
            }
            Event::End(TagEnd::TableRow) => s.push_str("</tr>\n"),
            Event::Start(Tag::TableCell) => {
                let end = find_end(events, i, |e| matches!(e, Event::End(TagEnd::TableCell)));
                let mut inner = String::new();
                pulldown_cmark::html::push_html(&mut inner, events[i + 1..end].iter().cloned());
                let text: String = events[i + 1..end]
                    .iter()
                    .filter_map(|e| match e {
                        Event::Text(t) | Event::Code(t) => Some(t.as_ref()),
                        _ => None,
                    })
                    .collect();
                let mut attrs = String::new();
                if let Some(a) = match align.get(column) {
                    Some(Alignment::Right) => Some("right"),
                    Some(Alignment::Center) => Some("center"),
                    Some(Alignment::Left) => Some("left"),
                    _ => None,
                } {
                    let _ = write!(attrs, " style=\"text-align: {a}\"");
                }
                if in_head {
                    let _ = write!(
                        s,
                        "<th{attrs} scope=\"col\" tabindex=\"0\" title=\"Sort by this column\">{inner}</th>"
                    );
                } else {
                    if text.contains('†') {
                        attrs.push_str(
                            " class=\"noisy\" title=\"Noisy: the median's 95 % interval is wider than ±5 %\"",
                        );
                    }
                    let _ = write!(s, "<td{attrs}>{inner}</td>");
                }
                column += 1;
                i = end;
            }
            _ => {}
        }
        i += 1;
    }
    s.push_str("</tbody></table></div>\n");
}

/// One choice of a viewer: a backend's image and maps against the reference, or the
/// reference's.
struct Pick<'r> {
    run: &'r Run,
    reference: bool,
    /// Its colour image (the reference's for a backend identical to it).
    image: String,
    /// The id-difference map, `None` where the ids all agree.
    ids: Option<String>,
    /// The FLIP map, `None` where the images are identical.
    flip: Option<String>,
    /// The heat map of node or cell visits per pixel, `None` where none was written.
    visits: Option<String>,
}

/// The image viewer of one workload (empty without a reference image).
fn viewer(results: &Results, key: &WorkloadKey) -> String {
    let runs = key.runs(results);
    let Some((reference, reference_image)) = runs.iter().find_map(|r| {
        (r.backend == r.reference)
            .then_some(r.images.color.as_ref())
            .flatten()
            .map(|c| (*r, c))
    }) else {
        return String::new();
    };
    let mut picks = vec![Pick {
        run: reference,
        reference: true,
        image: reference_image.clone(),
        ids: None,
        flip: None,
        visits: reference.images.visits.clone(),
    }];
    let mut absent = Vec::new();
    for r in runs.iter().filter(|r| !std::ptr::eq(**r, reference)) {
        let identical = r.equality.as_ref().is_some_and(|e| e.identical);
        match (&r.images.color, identical) {
            (_, true) => picks.push(Pick {
                run: r,
                reference: false,
                image: reference_image.clone(),
                ids: None,
                flip: None,
                visits: r.images.visits.clone(),
            }),
            (Some(color), false) => picks.push(Pick {
                run: r,
                reference: false,
                image: color.clone(),
                ids: r.images.ids_diff.clone(),
                flip: r.images.flip.clone(),
                visits: r.images.visits.clone(),
            }),
            (None, false) => absent.push(format!(
                "{} ({}{})",
                r.backend,
                r.status,
                r.reason
                    .as_deref()
                    .map(|why| format!(": {why}"))
                    .unwrap_or_default()
            )),
        }
    }
    let (w, h) = (key.width, key.height);
    // Small images start magnified (a 64 x 64 test image at 4x), large ones at 1x.
    let zoom = [1u32, 2, 4, 8]
        .into_iter()
        .find(|z| w * z >= 256)
        .unwrap_or(8);
    let id = format!(
        "viewer-{}-{}",
        crate::fmt::file_safe(&key.scene),
        crate::fmt::file_safe(&key.mode)
    );
    let mut s = String::new();
    let _ = write!(
        s,
        "<section class=\"viewer\" id=\"{id}\" data-scene=\"{}\" data-mode=\"{}\" tabindex=\"0\" \
         aria-label=\"Image viewer: {} {}\">",
        esc(&key.scene),
        esc(&key.mode),
        esc(&key.scene),
        esc(&key.mode)
    );
    let _ = write!(
        s,
        "<div class=\"viewer-bar\"><span class=\"viewer-title\">{} · {} · {w} x {h}, {} spp</span>",
        esc(&key.scene),
        esc(&key.mode),
        key.spp
    );
    s.push_str("<span class=\"viewer-picks\" role=\"group\" aria-label=\"Backend\">");
    for (n, p) in picks.iter().enumerate() {
        let d = |v: &Option<String>| v.as_deref().map(esc).unwrap_or_default();
        let _ = write!(
            s,
            "<button type=\"button\" class=\"viewer-pick{}\" data-backend=\"{}\"{} \
             data-image=\"{}\" data-ids=\"{}\" data-flip=\"{}\" data-visits=\"{}\" aria-pressed=\"{}\" \
             title=\"key {}\">{}{}</button>",
            pick_class(p),
            esc(&p.run.backend),
            if p.reference {
                " data-reference=\"true\""
            } else {
                ""
            },
            esc(&p.image),
            d(&p.ids),
            d(&p.flip),
            d(&p.visits),
            n == 0,
            if n < 9 {
                (n + 1).to_string()
            } else {
                "arrows".into()
            },
            esc(&p.run.backend),
            if p.reference { " (reference)" } else { "" }
        );
    }
    s.push_str("</span>");
    s.push_str(
        "<span class=\"viewer-layers\" role=\"group\" aria-label=\"Layer\">\
         <button type=\"button\" class=\"viewer-layer\" data-layer=\"image\" aria-pressed=\"true\" title=\"key i\">image</button>\
         <button type=\"button\" class=\"viewer-layer\" data-layer=\"ids\" aria-pressed=\"false\" title=\"key d\">id differences</button>\
         <button type=\"button\" class=\"viewer-layer\" data-layer=\"flip\" aria-pressed=\"false\" title=\"key f\">FLIP</button>",
    );
    // The visits layer only where some backend has a heat map of its camera rays' visits.
    if picks.iter().any(|p| p.visits.is_some()) {
        s.push_str(
            "<button type=\"button\" class=\"viewer-layer\" data-layer=\"visits\" aria-pressed=\"false\" title=\"key v\">visits</button>",
        );
    }
    s.push_str("</span>");
    let _ = write!(
        s,
        "<span class=\"viewer-zoom\"><button type=\"button\" class=\"viewer-zoom-out\" title=\"key -\">−</button>\
         <output class=\"viewer-zoom-level\">{zoom}x</output>\
         <button type=\"button\" class=\"viewer-zoom-in\" title=\"key +\">+</button></span></div>"
    );
    let first = &picks[0];
    let _ = write!(
        s,
        "<div class=\"viewer-body\"><div class=\"viewer-canvas\"><img class=\"viewer-image\" \
         src=\"{}\" alt=\"{} rendered by {}\" width=\"{}\" height=\"{}\" data-width=\"{w}\" \
         data-height=\"{h}\" data-zoom=\"{zoom}\" data-backend=\"{}\" data-layer=\"image\" \
         decoding=\"async\"></div>",
        esc(&first.image),
        esc(&key.scene),
        esc(&first.run.backend),
        w * zoom,
        h * zoom,
        esc(&first.run.backend)
    );
    let _ = write!(
        s,
        "<div class=\"viewer-side\"><div class=\"viewer-stats\" data-backend=\"{}\" aria-live=\"polite\">{}</div>\
         <p class=\"viewer-caption\"></p><p class=\"viewer-pixel\">pixel: move the pointer over the image</p>",
        esc(&first.run.backend),
        stats(first, reference)
    );
    for p in &picks {
        let _ = write!(
            s,
            "<template class=\"viewer-stats-for\" data-backend=\"{}\">{}</template>",
            esc(&p.run.backend),
            stats(p, reference)
        );
    }
    s.push_str(&keys_legend());
    s.push_str("</div></div>");
    if !absent.is_empty() {
        let _ = write!(
            s,
            "<p class=\"viewer-absent\">Not in the viewer (no image): {}</p>",
            esc(&absent.join("; "))
        );
    }
    if runs.iter().any(|r| !r.cameras.is_empty()) {
        s.push_str(
            "<p class=\"viewer-absent\">The images and maps are the first camera's; the \
             figures are over every camera.</p>",
        );
    }
    s.push_str("</section>");
    s
}

/// The pick button's extra class: how its result compares.
fn pick_class(p: &Pick) -> &'static str {
    match &p.run.equality {
        _ if p.reference => " is-reference",
        Some(e) if e.identical => " is-identical",
        Some(e) if e.pass => " is-pass",
        _ => " is-fail",
    }
}

/// The figures of one pick against the reference, as a description list.
fn stats(p: &Pick, reference: &Run) -> String {
    let r = p.run;
    let mut rows: Vec<(&str, String)> = vec![("backend", r.backend.clone())];
    if p.reference {
        rows.push(("role", "reference of this workload".into()));
    } else {
        rows.push((
            "contract",
            if r.exact {
                "exact (must be bit-identical)".into()
            } else {
                "peer (within tolerance)".into()
            },
        ));
    }
    if let Some(t) = &r.seconds {
        rows.push((
            "render time",
            format!(
                "{}{}{}",
                seconds(t.median),
                t.interval.map_or_else(
                    || " (one repetition: noise unknown)".to_string(),
                    |[lo, hi]| format!(
                        " [{} - {}] at {:.0}%",
                        seconds(lo),
                        seconds(hi),
                        t.confidence.unwrap_or(0.0) * 100.0
                    )
                ),
                crate::fmt::noisy_mark(t)
            ),
        ));
        rows.push(("repetitions", crate::fmt::repetitions(t)));
    }
    if let Some(t) = &r.device_seconds {
        rows.push((
            "device time",
            format!(
                "{}{}",
                seconds(t.median),
                if r.software_device {
                    " (software adapter)"
                } else {
                    ""
                }
            ),
        ));
    }
    if let Some(m) = r.mrays_per_s {
        rows.push(("Mrays/s", format!("{m:.2}")));
    }
    if let Some(t) = r.tests_per_ray {
        rows.push(("tests/ray", format!("{t:.1}")));
    }
    if let Some(e) = r.equality.as_ref().filter(|_| !p.reference) {
        rows.push(("against", format!("{} (reference)", reference.backend)));
        rows.push((
            "verdict",
            if e.identical {
                "bit-identical".into()
            } else if e.pass {
                "passes (within tolerance)".into()
            } else {
                "FAILS".into()
            },
        ));
        rows.push(("id match", format!("{:.4} %", e.id_match * 100.0)));
        rows.push(("hit / miss differ", e.hit_mismatch.to_string()));
        rows.push(("ties", e.tie_mismatch.to_string()));
        rows.push(("t differs (same id)", e.t_mismatch.to_string()));
        rows.push(("max |dt|", format!("{:.1e}", e.max_abs_dt)));
        rows.push((
            "PSNR",
            match e.psnr_db {
                Some(v) => format!("{v:.1} dB"),
                None => "inf (identical)".into(),
            },
        ));
        if let Some(f) = e.flip_mean {
            rows.push(("mean FLIP", format!("{f:.4}")));
        }
    }
    let mut s = String::from("<dl>");
    for (k, v) in rows {
        let _ = write!(s, "<dt>{}</dt><dd>{}</dd>", esc(k), esc(&v));
    }
    s.push_str("</dl>");
    s
}

/// Seconds in s, ms or µs.
fn seconds(s: f64) -> String {
    if s >= 1.0 {
        format!("{s:.3} s")
    } else if s >= 1e-3 {
        format!("{:.2} ms", s * 1e3)
    } else {
        format!("{:.1} µs", s * 1e6)
    }
}

/// The colour keys of the maps (id differences, FLIP, visits) and the keyboard's.
fn keys_legend() -> String {
    let stops: Vec<String> = crate::images::magma_stops(9)
        .iter()
        .enumerate()
        .map(|(i, [r, g, b])| format!("rgb({r},{g},{b}) {}%", i * 100 / 8))
        .collect();
    format!(
        "<div class=\"viewer-key viewer-key-ids\"><p>Id differences:</p><ul>\
         <li><span class=\"swatch\" style=\"background: #303030\"></span>same primitive (the reference, darkened)</li>\
         <li><span class=\"swatch\" style=\"background: rgb(255,140,0)\"></span>a different primitive</li>\
         <li><span class=\"swatch\" style=\"background: #fff\"></span>one hits, the other misses</li></ul></div>\
         <div class=\"viewer-key viewer-key-flip\"><p>FLIP error (magma):</p>\
         <div class=\"ramp\" style=\"background: linear-gradient(to right, {0})\"></div>\
         <div class=\"ramp-labels\"><span>0 (same)</span><span>0.5</span><span>1</span></div></div>\
         <div class=\"viewer-key viewer-key-visits\"><p>Node or cell visits per pixel (magma, linear \
         from 0 to the image's own largest count):</p>\
         <div class=\"ramp\" style=\"background: linear-gradient(to right, {0})\"></div>\
         <div class=\"ramp-labels\"><span>0</span><span>half the maximum</span><span>the maximum</span></div></div>\
         <p class=\"viewer-help\">Keys (click the viewer first): ←/→ or j/k backend, 1-9 pick, \
         r reference, i image, d id differences, f FLIP, v visits (where offered), +/− zoom.</p>",
        stops.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slugs_are_plain_and_unique_ids_are_made_from_them() {
        assert_eq!(
            slug("Summary: ray casting, camera rays, Mrays/s"),
            "summary-ray-casting-camera-rays-mrays-s"
        );
        assert_eq!(slug("!!"), "section");
        let md = "# T\n\n## Verdict\n\n## Scenes\n\n### a (1 primitives)\n\n## Scenes\n";
        let mut headings = Vec::new();
        let _ = name_headings(
            Parser::new_ext(md, Options::ENABLE_TABLES).collect(),
            &mut headings,
        );
        let ids: Vec<&str> = headings.iter().map(|h| h.id.as_str()).collect();
        assert_eq!(
            ids,
            ["t", "verdict", "scenes", "a-1-primitives", "scenes-2"]
        );
    }

    #[test]
    fn tables_sort_and_mark_noisy_cells() {
        let md = "| backend | s |\n|---|---:|\n| bvh | 1.0 † |\n| naive | 2.0 |\n";
        let events: Vec<Event> = Parser::new_ext(md, Options::ENABLE_TABLES).collect();
        let mut s = String::new();
        render(&events, Path::new("."), &mut s);
        assert!(s.contains("<table class=\"sortable\">"), "{s}");
        assert!(
            s.contains("<th style=\"text-align: right\" scope=\"col\""),
            "{s}"
        );
        assert_eq!(s.matches("class=\"noisy\"").count(), 1, "{s}");
        assert!(
            s.contains(">naive</td><td style=\"text-align: right\">2.0</td>"),
            "{s}"
        );
    }

    #[test]
    fn viewer_markers_become_placeholders() {
        let md = format!("a\n\n{VIEWER_BEGIN}3 -->\n\n<img src=\"x.png\">\n\n{VIEWER_END}\n\nb\n");
        let (text, viewers) = take_viewers(&md);
        assert_eq!(viewers.len(), 1);
        assert_eq!(viewers[0].0, 3);
        assert!(
            !text.contains("x.png") && text.contains(&viewers[0].1),
            "{text}"
        );
        assert!(text.starts_with("a\n") && text.ends_with("b\n"), "{text}");
    }
}
