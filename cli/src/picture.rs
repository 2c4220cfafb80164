//! Pictures: a [`Scene`] of lines, polygons, circles and text in pixels (y down), written as
//! SVG by hand, and rendered to PNG by `resvg` with the DejaVu Sans font embedded in the tool
//! (the `dejavu` crate ships it under its free licence), so PNG text never depends on the
//! fonts a machine has. Every item may carry a class and `data-*` attributes (the millimetres
//! it stands for), which is what the tests read back. [`write_scene`] writes a scene as the
//! files a subcommand was asked for.

use std::fmt::Write as _;
use std::path::Path;

use crate::error::Error;

/// The font every text is set in (embedded for PNG).
pub const FONT: &str = "DejaVu Sans";

/// How an item is painted.
#[derive(Debug, Clone, PartialEq)]
pub struct Style {
    /// Outline colour (CSS), or none.
    pub stroke: Option<&'static str>,
    /// Fill colour (CSS), or none.
    pub fill: Option<&'static str>,
    /// Outline width, px.
    pub width_px: f64,
    /// Dashed outline.
    pub dashed: bool,
    /// Opacity of the fill, 0..=1.
    pub fill_opacity: f64,
}

impl Style {
    /// An outline of this colour and width.
    pub fn stroke(colour: &'static str, width_px: f64) -> Style {
        Style {
            stroke: Some(colour),
            fill: None,
            width_px,
            dashed: false,
            fill_opacity: 1.0,
        }
    }

    /// A fill of this colour (and no outline).
    pub fn fill(colour: &'static str) -> Style {
        Style {
            stroke: None,
            fill: Some(colour),
            width_px: 0.0,
            dashed: false,
            fill_opacity: 1.0,
        }
    }

    /// The same, with an outline.
    pub fn outlined(mut self, colour: &'static str, width_px: f64) -> Style {
        self.stroke = Some(colour);
        self.width_px = width_px;
        self
    }

    /// The same, dashed.
    pub fn dashed(mut self) -> Style {
        self.dashed = true;
        self
    }

    /// The same, with a see-through fill.
    pub fn opacity(mut self, fill_opacity: f64) -> Style {
        self.fill_opacity = fill_opacity;
        self
    }
}

/// Where a text's anchor point is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Anchor {
    /// Text starts there.
    Start,
    /// Text is centred on it.
    Middle,
    /// Text ends there.
    End,
}

/// What is drawn (pixels, y down).
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// A straight line.
    Line([f64; 2], [f64; 2]),
    /// Connected points, closed into a polygon or not.
    Path {
        /// The points.
        points: Vec<[f64; 2]>,
        /// Closed (a polygon).
        closed: bool,
    },
    /// A circle: centre and radius.
    Circle([f64; 2], f64),
    /// Text (baseline at the point).
    Text {
        /// Where.
        at: [f64; 2],
        /// What.
        text: String,
        /// Size, px.
        size_px: f64,
        /// Alignment.
        anchor: Anchor,
        /// Turned by this many degrees (clockwise on screen).
        rotate_deg: f64,
    },
}

/// One item of a scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Item {
    /// What.
    pub shape: Shape,
    /// How.
    pub style: Style,
    /// Its class (e.g. `rod`), for readers of the SVG.
    pub class: &'static str,
    /// `data-*` attributes: name (without `data-`) and value.
    pub data: Vec<(String, String)>,
}

/// A picture.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// Width, px.
    pub width_px: f64,
    /// Height, px.
    pub height_px: f64,
    /// Items, painted in order.
    pub items: Vec<Item>,
}

impl Scene {
    /// An empty white picture.
    pub fn new(width_px: f64, height_px: f64) -> Scene {
        Scene {
            width_px,
            height_px,
            items: Vec::new(),
        }
    }

    /// Adds an item.
    pub fn add(&mut self, class: &'static str, shape: Shape, style: Style) -> &mut Item {
        self.items.push(Item {
            shape,
            style,
            class,
            data: Vec::new(),
        });
        let last = self.items.len() - 1;
        &mut self.items[last]
    }

    /// Adds a text in black.
    pub fn text(
        &mut self,
        class: &'static str,
        at: [f64; 2],
        text: &str,
        size_px: f64,
        anchor: Anchor,
    ) {
        self.add(
            class,
            Shape::Text {
                at,
                text: text.to_string(),
                size_px,
                anchor,
                rotate_deg: 0.0,
            },
            Style::fill("#000"),
        );
    }

    /// The picture as an SVG document.
    pub fn to_svg(&self) -> String {
        let (w, h) = (self.width_px, self.height_px);
        let mut out = format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" \
             viewBox=\"0 0 {w} {h}\" font-family=\"{FONT}\">\n\
             <rect class=\"background\" x=\"0\" y=\"0\" width=\"{w}\" height=\"{h}\" \
             fill=\"#fff\"/>\n"
        );
        for item in &self.items {
            let mut attributes = format!(" class=\"{}\"", item.class);
            for (name, value) in &item.data {
                let _ = write!(attributes, " data-{name}=\"{}\"", escape(value));
            }
            let s = &item.style;
            let paint = format!(
                " fill=\"{}\"{} stroke=\"{}\" stroke-width=\"{}\"{}",
                s.fill.unwrap_or("none"),
                if s.fill_opacity < 1.0 {
                    format!(" fill-opacity=\"{}\"", s.fill_opacity)
                } else {
                    String::new()
                },
                s.stroke.unwrap_or("none"),
                s.width_px,
                if s.dashed {
                    format!(
                        " stroke-dasharray=\"{} {}\"",
                        3.0 * s.width_px,
                        2.0 * s.width_px
                    )
                } else {
                    String::new()
                },
            );
            match &item.shape {
                Shape::Line(a, b) => {
                    let _ = writeln!(
                        out,
                        "<line{attributes} x1=\"{:.2}\" y1=\"{:.2}\" x2=\"{:.2}\" \
                         y2=\"{:.2}\"{paint} stroke-linecap=\"round\"/>",
                        a[0], a[1], b[0], b[1]
                    );
                }
                Shape::Path { points, closed } => {
                    let list: Vec<String> = points
                        .iter()
                        .map(|p| format!("{:.2},{:.2}", p[0], p[1]))
                        .collect();
                    let tag = if *closed { "polygon" } else { "polyline" };
                    let _ = writeln!(
                        out,
                        "<{tag}{attributes} points=\"{}\"{paint} stroke-linejoin=\"round\"/>",
                        list.join(" ")
                    );
                }
                Shape::Circle(c, r) => {
                    let _ = writeln!(
                        out,
                        "<circle{attributes} cx=\"{:.2}\" cy=\"{:.2}\" r=\"{r:.2}\"{paint}/>",
                        c[0], c[1]
                    );
                }
                Shape::Text {
                    at,
                    text,
                    size_px,
                    anchor,
                    rotate_deg,
                } => {
                    let anchor = match anchor {
                        Anchor::Start => "start",
                        Anchor::Middle => "middle",
                        Anchor::End => "end",
                    };
                    let rotate = if *rotate_deg != 0.0 {
                        format!(
                            " transform=\"rotate({rotate_deg} {:.2} {:.2})\"",
                            at[0], at[1]
                        )
                    } else {
                        String::new()
                    };
                    let _ = writeln!(
                        out,
                        "<text{attributes} x=\"{:.2}\" y=\"{:.2}\" font-size=\"{size_px}\" \
                         text-anchor=\"{anchor}\" fill=\"{}\"{rotate}>{}</text>",
                        at[0],
                        at[1],
                        s.fill.unwrap_or("#000"),
                        escape(text)
                    );
                }
            }
        }
        out.push_str("</svg>\n");
        out
    }
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// An SVG document rendered to PNG bytes, with the embedded font.
pub fn png(svg: &str) -> Result<Vec<u8>, String> {
    let mut options = resvg::usvg::Options {
        font_family: FONT.to_string(),
        ..resvg::usvg::Options::default()
    };
    let fonts = options.fontdb_mut();
    fonts.load_font_data(dejavu::sans::regular().to_vec());
    fonts.load_font_data(dejavu::sans::bold().to_vec());
    let tree = resvg::usvg::Tree::from_str(svg, &options).map_err(|e| e.to_string())?;
    let size = tree.size().to_int_size();
    let mut pixmap = resvg::tiny_skia::Pixmap::new(size.width(), size.height())
        .ok_or_else(|| "empty picture".to_string())?;
    resvg::render(
        &tree,
        resvg::tiny_skia::Transform::identity(),
        &mut pixmap.as_mut(),
    );
    pixmap.encode_png().map_err(|e| e.to_string())
}

/// Writes a scene as `stem.svg` and/or `stem.png`; the paths written.
pub fn write_scene(
    scene: &Scene,
    stem: &Path,
    as_svg: bool,
    as_png: bool,
) -> Result<Vec<String>, Error> {
    let text = scene.to_svg();
    let mut written = Vec::new();
    let file_problem = |path: &Path, error| Error::File {
        path: path.display().to_string(),
        error,
    };
    if as_svg {
        let path = stem.with_extension("svg");
        std::fs::write(&path, &text).map_err(|e| file_problem(&path, e))?;
        written.push(path.display().to_string());
    }
    if as_png {
        let path = stem.with_extension("png");
        let bytes = png(&text).map_err(|e| file_problem(&path, std::io::Error::other(e)))?;
        std::fs::write(&path, bytes).map_err(|e| file_problem(&path, e))?;
        written.push(path.display().to_string());
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Decodes a PNG with resvg's own decoder into RGBA pixels.
    fn pixels(png_bytes: &[u8]) -> Vec<u8> {
        resvg::tiny_skia::Pixmap::decode_png(png_bytes)
            .unwrap()
            .data()
            .to_vec()
    }

    #[test]
    fn png_text_is_drawn_with_the_embedded_font() {
        let mut scene = Scene::new(120.0, 40.0);
        let blank = png(&scene.to_svg()).unwrap();
        scene.text("label", [10.0, 28.0], "leg 3", 20.0, Anchor::Start);
        let with_text = png(&scene.to_svg()).unwrap();
        let dark = pixels(&with_text)
            .chunks(4)
            .filter(|p| p[0] < 128 && p[3] > 0)
            .count();
        // "leg 3" at 20 px covers well over a hundred pixels; a missing font draws none.
        assert!(dark > 100, "{dark} dark pixels");
        assert!(pixels(&blank).chunks(4).all(|p| p[0] == 255));
    }

    #[test]
    fn svg_items_carry_class_data_and_escaped_text() {
        let mut scene = Scene::new(10.0, 10.0);
        scene
            .add("joint", Shape::Circle([1.0, 2.0], 3.0), Style::fill("#123"))
            .data
            .push(("leg".into(), "4".into()));
        scene.text("title", [0.0, 5.0], "a < b & c", 8.0, Anchor::Middle);
        let svg = scene.to_svg();
        assert!(
            svg.contains(
                "<circle class=\"joint\" data-leg=\"4\" cx=\"1.00\" cy=\"2.00\" r=\"3.00\""
            ),
            "{svg}"
        );
        assert!(svg.contains(">a &lt; b &amp; c</text>"), "{svg}");
    }
}
