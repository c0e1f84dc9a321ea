//! The page: a title, the summary cards (the figures a user came for, each
//! with its meaning and a link to its plot), sections of text and plots,
//! and every figure of `run.json` in a folded table at the end, with
//! plotly.js embedded once in the head so the file works offline.

use plotly::{Layout, Plot, Trace};
use std::fmt::Write;

/// One HTML page under construction.
#[derive(Debug, Default)]
pub struct Page {
    title: String,
    /// What stands above the cards.
    intro: String,
    body: String,
    plots: usize,
}

/// One summary card: a figure of `run.json` (at `key`, a dotted path), as
/// shown, with a one-line meaning and the plot that shows it.
#[derive(Clone, Debug, PartialEq)]
pub struct Card {
    /// What the figure is.
    pub title: String,
    /// Its dotted path in `run.json` (`timings.total_s`).
    pub key: String,
    /// Its value there, as `run.json` holds it.
    pub value: serde_json::Value,
    /// The value as shown (`59.9 s`).
    pub shown: String,
    /// One line on what it means.
    pub meaning: String,
    /// The div id of its plot or section (`plot-timings`), if any.
    pub link: Option<String>,
}

impl Card {
    /// The card of `run`'s figure at `key`, shown by `show`; `None` when
    /// `run` has no such figure (or it is `null`).
    pub fn of(
        run: &serde_json::Value,
        key: &str,
        title: &str,
        show: impl Fn(&serde_json::Value) -> Option<String>,
        meaning: String,
        link: Option<&str>,
    ) -> Option<Self> {
        let value = lookup(run, key)?;
        if value.is_null() {
            return None;
        }
        Some(Self {
            title: title.to_owned(),
            key: key.to_owned(),
            shown: show(value)?,
            value: value.clone(),
            meaning,
            link: link.map(str::to_owned),
        })
    }
}

/// The value at the dotted path `key` of `run`.
pub fn lookup<'a>(run: &'a serde_json::Value, key: &str) -> Option<&'a serde_json::Value> {
    key.split('.').try_fold(run, |v, part| v.get(part))
}

/// Escape text for HTML.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

impl Page {
    /// An empty page.
    pub fn new(title: &str) -> Self {
        Self {
            title: title.to_owned(),
            ..Self::default()
        }
    }

    /// A section heading.
    pub fn heading(&mut self, text: &str) {
        let _ = writeln!(self.body, "<h2>{}</h2>", escape(text));
    }

    /// A paragraph of plain text above the summary cards.
    pub fn intro(&mut self, text: &str) {
        let _ = writeln!(self.intro, "<p>{}</p>", escape(text));
    }

    /// A paragraph of plain text.
    pub fn paragraph(&mut self, text: &str) {
        let _ = writeln!(self.body, "<p>{}</p>", escape(text));
    }

    /// A two-column table of keys and values.
    pub fn table(&mut self, rows: &[(String, String)]) {
        self.body.push_str("<table class=\"summary\">\n");
        for (k, v) in rows {
            let _ = writeln!(
                self.body,
                "<tr><th>{}</th><td>{}</td></tr>",
                escape(k),
                escape(v)
            );
        }
        self.body.push_str("</table>\n");
    }

    /// A table with a header row (`header`) and rows of cells, the first
    /// cell of each row a header cell.
    pub fn grid_table(&mut self, id: &str, header: &[String], rows: &[Vec<String>]) {
        let _ = writeln!(self.body, "<table class=\"summary\" id=\"{}\">", escape(id));
        self.body.push_str("<tr>");
        for h in header {
            let _ = write!(self.body, "<th>{}</th>", escape(h));
        }
        self.body.push_str("</tr>\n");
        for row in rows {
            self.body.push_str("<tr>");
            for (i, c) in row.iter().enumerate() {
                let tag = if i == 0 { "th" } else { "td" };
                let _ = write!(self.body, "<{tag}>{}</{tag}>", escape(c));
            }
            self.body.push_str("</tr>\n");
        }
        self.body.push_str("</table>\n");
    }

    /// A plot `height_px` tall, its div id `plot-<id>`; `class` lets the test
    /// and the style find the 3-D views. Returns the div id.
    pub fn plot(&mut self, id: &str, plot: &Plot, height_px: u32, class: &str) -> String {
        let div = format!("plot-{id}");
        let _ = writeln!(
            self.body,
            "<div class=\"plot {}\" style=\"height:{height_px}px\">{}</div>",
            escape(class),
            plot.to_inline_html(Some(&div))
        );
        self.plots += 1;
        div
    }

    /// Start a grid of small plots (closed by [`Page::end_grid`]).
    pub fn begin_grid(&mut self) {
        self.body.push_str("<div class=\"grid\">\n");
    }

    /// Close the grid opened by [`Page::begin_grid`].
    pub fn end_grid(&mut self) {
        self.body.push_str("</div>\n");
    }

    /// Number of plots on the page.
    pub fn plots(&self) -> usize {
        self.plots
    }

    /// The whole page, without summary cards or `run.json` table.
    pub fn finish(&self) -> String {
        self.finish_with(&[], None)
    }

    /// The whole page: the intro, the summary `cards`, the sections, and
    /// `run` (when given) flattened into a folded table at the end, the
    /// objects named in `skip` and arrays longer than 8 left out.
    pub fn finish_with(
        &self,
        cards: &[Card],
        run: Option<(&serde_json::Value, &[&str])>,
    ) -> String {
        let mut top = self.intro.clone();
        if !cards.is_empty() {
            top.push_str("<div class=\"cards\" id=\"summary-cards\">\n");
            for c in cards {
                let value = serde_json::to_string(&c.value).unwrap_or_default();
                let (open, close) = match &c.link {
                    Some(l) => (format!("<a class=\"card\" href=\"#{}\"", escape(l)), "</a>"),
                    None => ("<div class=\"card\"".to_owned(), "</div>"),
                };
                let _ = writeln!(
                    top,
                    "{open} data-key=\"{}\" data-value=\"{}\"><span class=\"card-title\">{}</span>\
                     <span class=\"card-value\">{}</span><span class=\"card-meaning\">{}</span>{close}",
                    escape(&c.key),
                    escape(&value),
                    escape(&c.title),
                    escape(&c.shown),
                    escape(&c.meaning),
                );
            }
            top.push_str("</div>\n");
        }
        let mut tail = String::new();
        if let Some((run, skip)) = run {
            let mut rows = Vec::new();
            flatten(run, "", skip, 8, &mut rows);
            tail.push_str(
                "<details id=\"run-json\"><summary>Every figure of run.json</summary>\n\
                 <table class=\"summary\">\n",
            );
            for (k, v) in rows {
                let _ = writeln!(
                    tail,
                    "<tr><th>{}</th><td>{}</td></tr>",
                    escape(&k),
                    escape(&v)
                );
            }
            tail.push_str("</table>\n</details>\n");
        }
        format!(
            "<!doctype html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
             <title>{title}</title>\n<style>{STYLE}</style>\n{js}</head>\n<body>\n\
             <h1>{title}</h1>\n{top}{body}{tail}</body>\n</html>\n",
            title = escape(&self.title),
            js = Plot::offline_js_sources(),
            body = self.body,
        )
    }
}

const STYLE: &str = "body{font-family:sans-serif;margin:1.5em;max-width:1400px;color:#222}\
table.summary{border-collapse:collapse;font-size:0.9em}\
table.summary th,table.summary td{border:1px solid #ccc;padding:2px 8px;text-align:left}\
table.summary th{background:#f3f3f3;font-weight:normal}\
div.plot{width:100%;margin-bottom:1em}\
div.grid{display:grid;grid-template-columns:repeat(auto-fill,minmax(440px,1fr));gap:8px}\
div.cards{display:grid;grid-template-columns:repeat(auto-fill,minmax(230px,1fr));gap:10px;margin:1em 0}\
.card{display:flex;flex-direction:column;border:1px solid #ccc;border-radius:6px;padding:8px 10px;\
color:inherit;text-decoration:none;background:#fafafa}\
a.card:hover{border-color:#1f77b4}\
.card-title{font-size:0.85em;color:#555}\
.card-value{font-size:1.5em;font-weight:bold;margin:2px 0}\
.card-meaning{font-size:0.8em;color:#444}\
details{margin-top:2em}summary{cursor:pointer;font-weight:bold}";

/// The layout of a 2-D plot: a title and its axes' titles, 380 px tall.
pub fn xy_layout(title: &str, x: &str, y: &str) -> Layout {
    Layout::new()
        .title(plotly::common::Title::with_text(title))
        .height(380)
        .x_axis(plotly::layout::Axis::new().title(plotly::common::Title::with_text(x)))
        .y_axis(plotly::layout::Axis::new().title(plotly::common::Title::with_text(y)))
}

/// A plot of `traces` with `layout`.
pub fn plot_of(traces: Vec<Box<dyn Trace>>, layout: Layout) -> Plot {
    let mut plot = Plot::new();
    plot.add_traces(traces);
    plot.set_layout(layout);
    plot
}

/// Flatten a JSON summary into `key.sub: value` rows; arrays longer than
/// `max_array` and objects named in `skip` are left out.
pub fn flatten(
    value: &serde_json::Value,
    prefix: &str,
    skip: &[&str],
    max_array: usize,
    out: &mut Vec<(String, String)>,
) {
    match value {
        serde_json::Value::Object(map) => {
            for (k, v) in map {
                if skip.contains(&k.as_str()) {
                    continue;
                }
                // A member named as its parent (`coverage.oracle.oracle`)
                // is shown one level up.
                let key = if prefix.is_empty() {
                    k.clone()
                } else if prefix.rsplit('.').next() == Some(k.as_str()) {
                    prefix.to_owned()
                } else {
                    format!("{prefix}.{k}")
                };
                flatten(v, &key, skip, max_array, out);
            }
        }
        serde_json::Value::Array(items) => {
            if items.len() <= max_array && items.iter().all(|v| !v.is_object()) {
                let cells: Vec<String> = items.iter().map(short).collect();
                out.push((prefix.to_owned(), format!("[{}]", cells.join(", "))));
            } else {
                out.push((prefix.to_owned(), format!("{} entries", items.len())));
            }
        }
        v => out.push((prefix.to_owned(), short(v))),
    }
}

/// A JSON scalar as short text (numbers to 4 significant figures).
fn short(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::Number(n) => match (n.as_i64(), n.as_f64()) {
            (Some(i), _) => i.to_string(),
            (None, Some(0.0)) => "0".to_owned(),
            (None, Some(x)) if x.abs() < 1e-3 || x.abs() >= 1e6 => format!("{x:.4e}"),
            (None, Some(x)) => {
                let digits = (3 - x.abs().log10().floor() as i32).clamp(0, 6);
                format!("{x:.*}", usize::try_from(digits).unwrap_or(0))
            }
            _ => n.to_string(),
        },
        serde_json::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup() {
        assert_eq!(
            escape("<a href='x'>&</a>"),
            "&lt;a href=&#39;x&#39;&gt;&amp;&lt;/a&gt;"
        );
    }

    #[test]
    fn flattens_nested_summary() {
        let v = serde_json::json!({"a": {"b": 0.123_456, "c": [1, 2], "a": {"e": 1}}, "d": "x", "big": [1, 2, 3], "skip": {"z": 1}, "zero": 0.0});
        let mut rows = Vec::new();
        flatten(&v, "", &["skip"], 2, &mut rows);
        assert_eq!(
            rows,
            vec![
                ("a.e".into(), "1".into()),
                ("a.b".into(), "0.1235".into()),
                ("a.c".into(), "[1, 2]".into()),
                ("big".into(), "3 entries".into()),
                ("d".into(), "x".into()),
                ("zero".into(), "0".into()),
            ]
        );
    }
}
