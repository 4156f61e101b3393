//! SVG figures: data points, tolerance regions, refined curves, active constraints and a caption.
//!
//! A [`Figure`] collects items in data coordinates, fits them into a fixed pixel frame (equal
//! aspect for parametric curves, free aspect for graphs of functions), draws light axes with tick
//! labels, a title and a caption, and renders to an SVG string with the `svg` crate.
//!
//! ```
//! use curvefit::plot::{Figure, Marker, Style};
//! let mut fig = Figure::new("a triangle");
//! fig.polygon(&[[0.0, 0.0], [1.0, 0.0], [0.5, 1.0]], Style::stroke("#1f77b4", 1.5));
//! fig.points(&[[0.0, 0.0]], Marker::Dot, Style::fill("black"));
//! fig.caption("E = 1.0");
//! let svg = fig.to_svg();
//! assert!(svg.starts_with("<svg"));
//! ```

use svg::node::element::{path::Data, Circle, Group, Line, Path, Rectangle, Text};
use svg::Document;

/// Colours used across curvefit's figures (a colour-blind-safe palette).
pub mod palette {
    /// Refined curve.
    pub const CURVE: &str = "#1f4e99";
    /// Data points.
    pub const DATA: &str = "#111111";
    /// Inactive tolerance regions.
    pub const REGION: &str = "#8c8c8c";
    /// Active constraints.
    pub const ACTIVE: &str = "#d1495b";
    /// A second curve for comparisons.
    pub const SECOND: &str = "#e69f00";
    /// A third curve for comparisons.
    pub const THIRD: &str = "#009e73";
    /// Extra knots / markers.
    pub const KNOT: &str = "#cc3311";
    /// Bounds of a strip.
    pub const BOUND: &str = "#555555";
}

/// Stroke and fill of an item.
#[derive(Clone, Debug, PartialEq)]
pub struct Style {
    /// Stroke colour (none when `None`).
    pub stroke: Option<String>,
    /// Stroke width in pixels.
    pub width: f64,
    /// Fill colour (none when `None`).
    pub fill: Option<String>,
    /// Fill opacity in [0, 1].
    pub fill_opacity: f64,
    /// SVG dash pattern, e.g. `"4 3"`.
    pub dash: Option<String>,
}

impl Style {
    /// A stroked outline of the given colour and pixel width.
    pub fn stroke(color: &str, width: f64) -> Self {
        Style {
            stroke: Some(color.into()),
            width,
            fill: None,
            fill_opacity: 1.0,
            dash: None,
        }
    }
    /// A filled shape without outline.
    pub fn fill(color: &str) -> Self {
        Style {
            stroke: None,
            width: 0.0,
            fill: Some(color.into()),
            fill_opacity: 1.0,
            dash: None,
        }
    }
    /// Adds a translucent fill.
    pub fn with_fill(mut self, color: &str, opacity: f64) -> Self {
        self.fill = Some(color.into());
        self.fill_opacity = opacity;
        self
    }
    /// Makes the stroke dashed.
    pub fn dashed(mut self, pattern: &str) -> Self {
        self.dash = Some(pattern.into());
        self
    }
}

/// Point markers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    /// A filled dot.
    Dot,
    /// An open circle.
    Ring,
    /// A filled square.
    Square,
    /// A diagonal cross.
    Cross,
    /// A six-pointed asterisk (the seeds' "*" for extra knots).
    Star,
    /// A filled triangle pointing up.
    TriangleUp,
    /// A filled triangle pointing down.
    TriangleDown,
    /// A filled diamond.
    Diamond,
}

/// What a legend entry shows next to its text: the mark as it is drawn in the figure.
#[derive(Clone, Debug, PartialEq)]
pub enum Swatch {
    /// A line in the item's stroke (dashed if the item is).
    Line(Style),
    /// A marker of the given pixel size.
    Marker(Marker, f64, Style),
    /// A region: a small filled, outlined square.
    Region(Style),
}

#[derive(Clone, Debug)]
enum Item {
    Polyline {
        pts: Vec<[f64; 2]>,
        closed: bool,
        style: Style,
    },
    Points {
        pts: Vec<[f64; 2]>,
        marker: Marker,
        size: f64,
        style: Style,
    },
    Circle {
        center: [f64; 2],
        radius: f64,
        style: Style,
    },
    Label {
        at: [f64; 2],
        text: String,
        color: String,
    },
}

/// A figure in data coordinates, rendered to SVG by [`Figure::to_svg`].
#[derive(Clone, Debug)]
pub struct Figure {
    title: String,
    captions: Vec<String>,
    fields: Vec<Vec<(String, String)>>,
    legend: Vec<(String, Swatch)>,
    labels: Option<(String, String)>,
    items: Vec<Item>,
    equal_aspect: bool,
    width: f64,
    height: f64,
    axes: bool,
}

/// Pixel margins: left (tick labels, axis label), right, top (title), bottom (ticks, axis label).
const MARGIN_LEFT: f64 = 70.0;
const MARGIN_RIGHT: f64 = 16.0;
const MARGIN_TOP: f64 = 34.0;
const MARGIN_BOTTOM: f64 = 50.0;
const CAPTION_LINE: f64 = 16.0;

impl Figure {
    /// An empty 640×480 figure with equal aspect ratio and axes.
    pub fn new(title: &str) -> Self {
        Figure {
            title: title.into(),
            captions: Vec::new(),
            fields: Vec::new(),
            legend: Vec::new(),
            labels: None,
            items: Vec::new(),
            equal_aspect: true,
            width: 640.0,
            height: 480.0,
            axes: true,
        }
    }

    /// Equal scales on both axes (parametric curves; default) or independent scales (graphs).
    pub fn equal_aspect(&mut self, on: bool) -> &mut Self {
        self.equal_aspect = on;
        self
    }

    /// Pixel size of the plotting frame (without caption lines).
    pub fn size(&mut self, width: f64, height: f64) -> &mut Self {
        self.width = width.max(100.0);
        self.height = height.max(100.0);
        self
    }

    /// Draw axes with tick labels (default) or not.
    pub fn axes(&mut self, on: bool) -> &mut Self {
        self.axes = on;
        self
    }

    /// An open polyline through `pts`.
    pub fn polyline(&mut self, pts: &[[f64; 2]], style: Style) -> &mut Self {
        self.items.push(Item::Polyline {
            pts: pts.to_vec(),
            closed: false,
            style,
        });
        self
    }

    /// A closed polygon through `pts`.
    pub fn polygon(&mut self, pts: &[[f64; 2]], style: Style) -> &mut Self {
        self.items.push(Item::Polyline {
            pts: pts.to_vec(),
            closed: true,
            style,
        });
        self
    }

    /// A line segment.
    pub fn segment(&mut self, a: [f64; 2], b: [f64; 2], style: Style) -> &mut Self {
        self.polyline(&[a, b], style)
    }

    /// Markers at `pts` (size 5 px).
    pub fn points(&mut self, pts: &[[f64; 2]], marker: Marker, style: Style) -> &mut Self {
        self.points_sized(pts, marker, 5.0, style)
    }

    /// Markers at `pts` with the given pixel size.
    pub fn points_sized(
        &mut self,
        pts: &[[f64; 2]],
        marker: Marker,
        size: f64,
        style: Style,
    ) -> &mut Self {
        self.items.push(Item::Points {
            pts: pts.to_vec(),
            marker,
            size,
            style,
        });
        self
    }

    /// A circle of `radius` data units (drawn as an ellipse if the aspect is not equal).
    pub fn circle(&mut self, center: [f64; 2], radius: f64, style: Style) -> &mut Self {
        self.items.push(Item::Circle {
            center,
            radius,
            style,
        });
        self
    }

    /// A text label at a data position.
    pub fn label(&mut self, at: [f64; 2], text: &str, color: &str) -> &mut Self {
        self.items.push(Item::Label {
            at,
            text: text.into(),
            color: color.into(),
        });
        self
    }

    /// Adds a caption line under the plot (e.g. the energy).
    pub fn caption(&mut self, text: &str) -> &mut Self {
        self.captions.push(text.into());
        self
    }

    /// Names the axes (drawn under the x ticks and, rotated, left of the y ticks).
    pub fn axis_labels(&mut self, x: &str, y: &str) -> &mut Self {
        self.labels = Some((x.into(), y.into()));
        self
    }

    /// Adds a caption line of named values, laid out in equal columns (`name: value`).
    pub fn caption_fields(&mut self, fields: &[(&str, String)]) -> &mut Self {
        self.fields.push(
            fields
                .iter()
                .map(|(k, v)| (k.to_string(), v.clone()))
                .collect(),
        );
        self
    }

    /// Adds a legend entry for a line (drawn top-right).
    pub fn legend(&mut self, text: &str, style: Style) -> &mut Self {
        self.legend.push((text.into(), Swatch::Line(style)));
        self
    }

    /// Adds a legend entry for a marker, drawn as in [`Figure::points_sized`].
    pub fn legend_marker(
        &mut self,
        text: &str,
        marker: Marker,
        size: f64,
        style: Style,
    ) -> &mut Self {
        self.legend
            .push((text.into(), Swatch::Marker(marker, size, style)));
        self
    }

    /// Adds a legend entry for a region (a filled, outlined shape).
    pub fn legend_region(&mut self, text: &str, style: Style) -> &mut Self {
        self.legend.push((text.into(), Swatch::Region(style)));
        self
    }

    fn bounds(&self) -> Option<[f64; 4]> {
        let mut b = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        let mut grow = |p: [f64; 2], r: f64| {
            if p[0].is_finite() && p[1].is_finite() && r.is_finite() {
                b[0] = b[0].min(p[0] - r);
                b[1] = b[1].min(p[1] - r);
                b[2] = b[2].max(p[0] + r);
                b[3] = b[3].max(p[1] + r);
            }
        };
        for it in &self.items {
            match it {
                Item::Polyline { pts, .. } | Item::Points { pts, .. } => {
                    pts.iter().for_each(|&p| grow(p, 0.0))
                }
                Item::Circle { center, radius, .. } => grow(*center, radius.abs()),
                Item::Label { at, .. } => grow(*at, 0.0),
            }
        }
        (b[0] <= b[2]).then_some(b)
    }

    /// Renders the figure as an SVG document string.
    pub fn to_svg(&self) -> String {
        let (w, h) = (self.width, self.height);
        let lines = self.captions.len() + self.fields.len();
        let total_h = h + CAPTION_LINE * lines as f64;
        // The legend gets its own column right of the plot, so it never hides a mark.
        let plot_w = w;
        let w = if self.legend.is_empty() {
            w
        } else {
            w + LEGEND_WIDTH + 8.0
        };
        let frame = [
            MARGIN_LEFT,
            MARGIN_TOP,
            plot_w - MARGIN_RIGHT,
            h - MARGIN_BOTTOM,
        ];
        let mut doc = Document::new()
            .set("width", w)
            .set("height", total_h)
            .set("viewBox", (0.0, 0.0, w, total_h))
            .set("font-family", "Helvetica, Arial, sans-serif")
            .add(
                Rectangle::new()
                    .set("width", w)
                    .set("height", total_h)
                    .set("fill", "white"),
            );
        doc = doc.add(
            Text::new(self.title.as_str())
                .set("x", w / 2.0)
                .set("y", 22.0)
                .set("text-anchor", "middle")
                .set("font-size", 15),
        );
        let map = Mapping::new(
            self.bounds().unwrap_or([0.0, 0.0, 1.0, 1.0]),
            frame,
            self.equal_aspect,
        );
        if self.axes {
            doc = doc.add(map.axes(frame));
        }
        if let Some((x, y)) = &self.labels {
            let cx = (frame[0] + frame[2]) / 2.0;
            let cy = (frame[1] + frame[3]) / 2.0;
            doc = doc
                .add(
                    Text::new(x.as_str())
                        .set("x", cx)
                        .set("y", frame[3] + 32.0)
                        .set("text-anchor", "middle")
                        .set("font-size", 12)
                        .set("font-style", "italic"),
                )
                .add(
                    Text::new(y.as_str())
                        .set("x", 0)
                        .set("y", 0)
                        .set("text-anchor", "middle")
                        .set("font-size", 12)
                        .set("font-style", "italic")
                        .set(
                            "transform",
                            format!("translate({} {cy}) rotate(-90)", frame[0] - 50.0),
                        ),
                );
        }
        let mut g = Group::new();
        for it in &self.items {
            g = match it {
                Item::Polyline { pts, closed, style } => {
                    let mut data = Data::new();
                    let mut first = true;
                    for &p in pts.iter().filter(|p| p[0].is_finite() && p[1].is_finite()) {
                        let q = map.px(p);
                        data = if first {
                            data.move_to((q[0], q[1]))
                        } else {
                            data.line_to((q[0], q[1]))
                        };
                        first = false;
                    }
                    if *closed && !first {
                        data = data.close();
                    }
                    if first {
                        g
                    } else {
                        g.add(styled(Path::new().set("d", data), style, *closed))
                    }
                }
                Item::Points {
                    pts,
                    marker,
                    size,
                    style,
                } => {
                    let mut gg = g;
                    for &p in pts {
                        if p[0].is_finite() && p[1].is_finite() {
                            gg = gg.add(marker_node(map.px(p), *marker, *size, style));
                        }
                    }
                    gg
                }
                Item::Circle {
                    center,
                    radius,
                    style,
                } => {
                    let c = map.px(*center);
                    let (rx, ry) = (radius * map.sx, radius * map.sy);
                    let e = svg::node::element::Ellipse::new()
                        .set("cx", c[0])
                        .set("cy", c[1])
                        .set("rx", rx.abs())
                        .set("ry", ry.abs());
                    g.add(styled(e, style, true))
                }
                Item::Label { at, text, color } => {
                    let p = map.px(*at);
                    g.add(
                        Text::new(text.as_str())
                            .set("x", p[0] + 4.0)
                            .set("y", p[1] - 4.0)
                            .set("font-size", 11)
                            .set("fill", color.as_str()),
                    )
                }
            };
        }
        doc = doc.add(g);
        if !self.legend.is_empty() {
            // A white box behind the legend keeps it readable over the curve.
            let x = plot_w + 4.0;
            doc = doc.add(
                Rectangle::new()
                    .set("x", x - 6.0)
                    .set("y", MARGIN_TOP + 2.0)
                    .set("width", LEGEND_WIDTH)
                    .set("height", 16.0 * self.legend.len() as f64 + 6.0)
                    .set("fill", "white")
                    .set("fill-opacity", 0.85)
                    .set("stroke", "#dddddd")
                    .set("stroke-width", 1),
            );
        }
        for (k, (text, swatch)) in self.legend.iter().enumerate() {
            let y = MARGIN_TOP + 16.0 + 16.0 * k as f64;
            let x = plot_w + 4.0;
            doc = match swatch {
                Swatch::Line(style) => {
                    let line = Line::new()
                        .set("x1", x)
                        .set("y1", y - 4.0)
                        .set("x2", x + 22.0)
                        .set("y2", y - 4.0);
                    doc.add(styled(line, &line_style(style), false))
                }
                Swatch::Marker(marker, size, style) => {
                    doc.add(marker_node([x + 11.0, y - 4.0], *marker, *size, style))
                }
                Swatch::Region(style) => doc.add(styled(
                    Rectangle::new()
                        .set("x", x + 5.0)
                        .set("y", y - 10.0)
                        .set("width", 12)
                        .set("height", 12),
                    style,
                    true,
                )),
            }
            .add(
                Text::new(text.as_str())
                    .set("x", x + 28.0)
                    .set("y", y)
                    .set("font-size", 11),
            );
        }
        let mut line = 0;
        for c in &self.captions {
            doc = doc.add(
                Text::new(c.as_str())
                    .set("x", w / 2.0)
                    .set("y", h + CAPTION_LINE * line as f64 + 4.0)
                    .set("text-anchor", "middle")
                    .set("font-size", 12),
            );
            line += 1;
        }
        for fields in &self.fields {
            let y = h + CAPTION_LINE * line as f64 + 4.0;
            let col = (w - 2.0 * MARGIN_RIGHT) / fields.len().max(1) as f64;
            for (k, (name, value)) in fields.iter().enumerate() {
                let x = MARGIN_RIGHT + col * (k as f64 + 0.5);
                doc = doc.add(
                    Text::new("")
                        .set("x", x)
                        .set("y", y)
                        .set("text-anchor", "middle")
                        .set("font-size", 12)
                        .add(
                            svg::node::element::TSpan::new(format!("{name}: "))
                                .set("fill", "#555555"),
                        )
                        .add(svg::node::element::TSpan::new(value.as_str())),
                );
            }
            line += 1;
        }
        doc.to_string()
    }
}

/// Pixel width of the legend box.
const LEGEND_WIDTH: f64 = 210.0;

/// Legend swatch: a line in the item's stroke (or fill) colour.
fn line_style(s: &Style) -> Style {
    let color = s
        .stroke
        .clone()
        .or_else(|| s.fill.clone())
        .unwrap_or_else(|| "black".into());
    Style {
        stroke: Some(color),
        width: s.width.max(2.0),
        fill: None,
        fill_opacity: 1.0,
        dash: s.dash.clone(),
    }
}

fn styled<T: svg::Node>(mut node: T, s: &Style, fillable: bool) -> T {
    node.assign("stroke", s.stroke.clone().unwrap_or_else(|| "none".into()));
    node.assign("stroke-width", s.width);
    node.assign("stroke-linejoin", "round");
    match (&s.fill, fillable) {
        (Some(f), true) => {
            node.assign("fill", f.clone());
            node.assign("fill-opacity", s.fill_opacity);
        }
        _ => node.assign("fill", "none"),
    }
    if let Some(d) = &s.dash {
        node.assign("stroke-dasharray", d.clone());
    }
    node
}

fn marker_node(p: [f64; 2], marker: Marker, size: f64, s: &Style) -> Group {
    let color = s
        .fill
        .clone()
        .or_else(|| s.stroke.clone())
        .unwrap_or_else(|| "black".into());
    let r = size / 2.0;
    let g = Group::new();
    match marker {
        Marker::Dot => g.add(
            Circle::new()
                .set("cx", p[0])
                .set("cy", p[1])
                .set("r", r)
                .set("fill", color),
        ),
        Marker::Ring => g.add(
            Circle::new()
                .set("cx", p[0])
                .set("cy", p[1])
                .set("r", r)
                .set("fill", "white")
                .set("stroke", color)
                .set("stroke-width", 1.3),
        ),
        Marker::Square => g.add(
            Rectangle::new()
                .set("x", p[0] - r)
                .set("y", p[1] - r)
                .set("width", size)
                .set("height", size)
                .set("fill", color),
        ),
        Marker::TriangleUp | Marker::TriangleDown | Marker::Diamond => {
            let r = 1.2 * r;
            let pts = match marker {
                Marker::TriangleUp => vec![(0.0, -r), (r, 0.8 * r), (-r, 0.8 * r)],
                Marker::TriangleDown => vec![(0.0, r), (r, -0.8 * r), (-r, -0.8 * r)],
                _ => vec![(0.0, -r), (r, 0.0), (0.0, r), (-r, 0.0)],
            };
            let mut data = Data::new().move_to((p[0] + pts[0].0, p[1] + pts[0].1));
            for &(dx, dy) in &pts[1..] {
                data = data.line_to((p[0] + dx, p[1] + dy));
            }
            g.add(
                Path::new()
                    .set("d", data.close())
                    .set("fill", color)
                    .set("stroke", "white")
                    .set("stroke-width", 0.6),
            )
        }
        Marker::Cross | Marker::Star => {
            let mut data = Data::new()
                .move_to((p[0] - r, p[1] - r))
                .line_to((p[0] + r, p[1] + r))
                .move_to((p[0] - r, p[1] + r))
                .line_to((p[0] + r, p[1] - r));
            if marker == Marker::Star {
                data = data
                    .move_to((p[0], p[1] - 1.3 * r))
                    .line_to((p[0], p[1] + 1.3 * r));
            }
            g.add(
                Path::new()
                    .set("d", data)
                    .set("stroke", color)
                    .set("stroke-width", 1.6)
                    .set("fill", "none"),
            )
        }
    }
}

/// Affine map from data to pixels (y up in data, down in pixels).
struct Mapping {
    x0: f64,
    y0: f64,
    sx: f64,
    sy: f64,
    px0: f64,
    py0: f64,
    bounds: [f64; 4],
}

impl Mapping {
    fn new(b: [f64; 4], frame: [f64; 4], equal: bool) -> Self {
        let (mut bw, mut bh) = (b[2] - b[0], b[3] - b[1]);
        let scale = bw.abs().max(bh.abs()).max(1e-300);
        if bw <= 1e-12 * scale {
            bw = if scale > 1e-300 { scale * 0.1 } else { 1.0 };
        }
        if bh <= 1e-12 * scale {
            bh = if scale > 1e-300 { scale * 0.1 } else { 1.0 };
        }
        // 4% padding on every side.
        let (cx, cy) = ((b[0] + b[2]) / 2.0, (b[1] + b[3]) / 2.0);
        let (bw, bh) = (bw * 1.08, bh * 1.08);
        let (fw, fh) = (frame[2] - frame[0], frame[3] - frame[1]);
        let (mut sx, mut sy) = (fw / bw, fh / bh);
        if equal {
            let s = sx.min(sy);
            sx = s;
            sy = s;
        }
        let bounds = [
            cx - fw / sx / 2.0,
            cy - fh / sy / 2.0,
            cx + fw / sx / 2.0,
            cy + fh / sy / 2.0,
        ];
        Mapping {
            x0: cx,
            y0: cy,
            sx,
            sy,
            px0: (frame[0] + frame[2]) / 2.0,
            py0: (frame[1] + frame[3]) / 2.0,
            bounds,
        }
    }

    fn px(&self, p: [f64; 2]) -> [f64; 2] {
        [
            self.px0 + (p[0] - self.x0) * self.sx,
            self.py0 - (p[1] - self.y0) * self.sy,
        ]
    }

    fn axes(&self, frame: [f64; 4]) -> Group {
        let mut g = Group::new();
        g = g.add(
            Rectangle::new()
                .set("x", frame[0])
                .set("y", frame[1])
                .set("width", frame[2] - frame[0])
                .set("height", frame[3] - frame[1])
                .set("fill", "none")
                .set("stroke", "#cccccc")
                .set("stroke-width", 1),
        );
        for (axis, (lo, hi)) in [
            (0, (self.bounds[0], self.bounds[2])),
            (1, (self.bounds[1], self.bounds[3])),
        ] {
            for v in ticks(lo, hi) {
                let label = Text::new(fmt_tick(v))
                    .set("font-size", 10)
                    .set("fill", "#555555");
                if axis == 0 {
                    let x = self.px([v, self.y0])[0];
                    g = g.add(line(x, frame[3], x, frame[3] + 4.0)).add(
                        label
                            .set("x", x)
                            .set("y", frame[3] + 15.0)
                            .set("text-anchor", "middle"),
                    );
                } else {
                    let y = self.px([self.x0, v])[1];
                    g = g.add(line(frame[0] - 4.0, y, frame[0], y)).add(
                        label
                            .set("x", frame[0] - 6.0)
                            .set("y", y + 3.0)
                            .set("text-anchor", "end"),
                    );
                }
            }
        }
        g
    }
}

fn line(x1: f64, y1: f64, x2: f64, y2: f64) -> Line {
    Line::new()
        .set("x1", x1)
        .set("y1", y1)
        .set("x2", x2)
        .set("y2", y2)
        .set("stroke", "#999999")
        .set("stroke-width", 1)
}

/// "Nice" tick values covering [lo, hi] (about five of them).
fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let span = hi - lo;
    if !(span.is_finite() && span > 0.0) {
        return Vec::new();
    }
    let raw = span / 5.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| span / s <= 6.0)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

fn fmt_tick(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        format!("{v:.1e}")
    } else {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        if s == "-0" {
            "0".into()
        } else {
            s.into()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_cover_range_with_round_steps() {
        let t = ticks(0.0, 1.0);
        assert!(t.len() >= 3 && t.len() <= 7, "{t:?}");
        assert!((t[1] - t[0] - 0.2).abs() < 1e-12);
        assert!(ticks(1.0, 1.0).is_empty());
    }

    #[test]
    fn svg_contains_items_and_caption() {
        let mut f = Figure::new("t");
        f.polyline(&[[0.0, 0.0], [1.0, 2.0]], Style::stroke("red", 1.0))
            .circle([0.5, 0.5], 0.1, Style::stroke("blue", 1.0))
            .points(&[[0.0, 0.0]], Marker::Star, Style::fill("black"))
            .caption("E = 3 <ok>");
        let s = f.to_svg();
        assert!(
            s.contains("<path") && s.contains("<ellipse") && s.contains("E = 3 &lt;ok&gt;"),
            "{s}"
        );
    }

    #[test]
    fn degenerate_and_nonfinite_input_does_not_panic() {
        let mut f = Figure::new("single point");
        f.points(
            &[[1.0, 1.0], [f64::NAN, 0.0]],
            Marker::Dot,
            Style::fill("black"),
        );
        assert!(f.to_svg().contains("<circle"));
        assert!(Figure::new("empty").to_svg().starts_with("<svg"));
    }
}
