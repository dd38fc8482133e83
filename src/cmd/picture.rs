//! The pictures of the command (`run --plot`, `stand --plot`) in either format: SVG from
//! plotters' SVG backend, PNG from its bitmap backend with the text set in a font built into
//! the command, encoded by the `png` crate; and the parts the pictures share (the legend
//! column, the panels' common time axis, the tick labels).

use plotters::coord::Shift;
use plotters::prelude::*;
// By path only: its traits in scope would make the colours' `stroke_width` ambiguous.
use plotters_backend as backend;

/// The width and height of the picture, pixels, in the SVG and the PNG alike. plotters has no
/// scale factor: a sharper PNG at twice the size would need every size in the drawing (fonts,
/// margins, strokes, the legend's) doubled, and at 1400 × 1000 the text is readable as it is.
pub const SIZE: (u32, u32) = (1400, 1000);

/// The formats the plot is drawn in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// SVG, text that a browser or an editor shows at any size.
    Svg,
    /// PNG, pixels: for a README, a chat or a report that takes no SVG.
    Png,
}

/// The format of a `--plot` file, by its extension (in any case): `.svg` or `.png`. A name
/// without an extension (`/dev/null`, `-`) gets SVG. Another extension (`run.jpg`) is
/// refused, rather than writing SVG or PNG under a name that promises something else.
pub fn format_of(path: &std::path::Path) -> Result<Format, String> {
    match path.extension().and_then(|e| e.to_str()) {
        None => Ok(Format::Svg),
        Some(e) if e.eq_ignore_ascii_case("svg") => Ok(Format::Svg),
        Some(e) if e.eq_ignore_ascii_case("png") => Ok(Format::Png),
        Some(_) => Err(format!(
            "--plot {}: the plot is drawn as SVG or PNG; name the file .svg or .png \
             (e.g. run.svg, run.png)",
            path.display()
        )),
    }
}

/// A picture that draws itself on either backend: the run's, the stand's.
pub(super) trait Picture {
    /// Draws the whole picture on `root`.
    fn draw_on<DB: DrawingBackend>(&self, root: &Area<DB>) -> DrawResult
    where
        DB::ErrorType: 'static;
}

/// Draws `picture` in `format`, [`SIZE`]: the file's bytes.
pub(super) fn render(picture: &impl Picture, format: Format) -> Result<Vec<u8>, String> {
    let drawing = |e: &dyn std::fmt::Display| format!("drawing the plot: {e}");
    match format {
        Format::Svg => {
            let mut svg = String::new();
            {
                let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
                picture.draw_on(&root).map_err(|e| drawing(&e))?;
                root.present().map_err(|e| drawing(&e))?;
            }
            Ok(svg.into_bytes())
        }
        Format::Png => {
            let font = ab_glyph::FontRef::try_from_slice(FONT)
                .map_err(|e| format!("the plot's built-in font: {e}"))?;
            let (w, h) = SIZE;
            let mut rgb = vec![0; w as usize * h as usize * 3];
            {
                let bitmap = BitMapBackend::with_buffer(&mut rgb, SIZE);
                let root = Pixels { bitmap, font }.into_drawing_area();
                picture.draw_on(&root).map_err(|e| drawing(&e))?;
                root.present().map_err(|e| drawing(&e))?;
            }
            encode_png(&rgb, SIZE).map_err(|e| format!("encoding the plot as PNG: {e}"))
        }
    }
}

/// The font of the PNG's text: DejaVu Sans, cut down to the characters a plot draws
/// (src/cmd/fonts/README.md). Built into the command, so that the PNG is the same on every
/// machine, whatever fonts it has.
const FONT: &[u8] = include_bytes!("fonts/DejaVuSans-subset.ttf");

/// `rgb` (3 bytes a pixel, row by row) as a PNG file.
fn encode_png(rgb: &[u8], (w, h): (u32, u32)) -> Result<Vec<u8>, png::EncodingError> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(rgb)?;
    writer.finish()?;
    Ok(out)
}

/// plotters' bitmap backend, with the text set in [`FONT`] as the SVG's viewer sets it.
///
/// plotters' own text on a bitmap (its `ab_glyph` feature) places each glyph without its
/// left side bearing, which spaces the letters unevenly ("fl oor"), and once enabled it
/// measures the text by the font on every backend, which moves the SVG's titles and labels
/// by a pixel. Here plotters lays out both pictures alike, by its estimate of the text's
/// size without a font, and only the PNG's text is drawn by the font: in every family and
/// style the drawing names (all `sans-serif`, normal), at the SVG's size (`font-size` =
/// plotters' size / 1.24), anchored as the SVG anchors it.
struct Pixels<'a> {
    bitmap: BitMapBackend<'a>,
    font: ab_glyph::FontRef<'static>,
}

impl DrawingBackend for Pixels<'_> {
    type ErrorType = <BitMapBackend<'static> as DrawingBackend>::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.bitmap.get_size()
    }

    fn ensure_prepared(&mut self) -> Result<(), backend::DrawingErrorKind<Self::ErrorType>> {
        self.bitmap.ensure_prepared()
    }

    fn present(&mut self) -> Result<(), backend::DrawingErrorKind<Self::ErrorType>> {
        self.bitmap.present()
    }

    fn draw_pixel(
        &mut self,
        point: backend::BackendCoord,
        color: backend::BackendColor,
    ) -> Result<(), backend::DrawingErrorKind<Self::ErrorType>> {
        self.bitmap.draw_pixel(point, color)
    }

    fn draw_line<S: backend::BackendStyle>(
        &mut self,
        from: backend::BackendCoord,
        to: backend::BackendCoord,
        style: &S,
    ) -> Result<(), backend::DrawingErrorKind<Self::ErrorType>> {
        self.bitmap.draw_line(from, to, style)
    }

    fn draw_rect<S: backend::BackendStyle>(
        &mut self,
        upper_left: backend::BackendCoord,
        bottom_right: backend::BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), backend::DrawingErrorKind<Self::ErrorType>> {
        self.bitmap.draw_rect(upper_left, bottom_right, style, fill)
    }

    fn draw_path<S: backend::BackendStyle, I: IntoIterator<Item = backend::BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), backend::DrawingErrorKind<Self::ErrorType>> {
        self.bitmap.draw_path(path, style)
    }

    fn draw_circle<S: backend::BackendStyle>(
        &mut self,
        center: backend::BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), backend::DrawingErrorKind<Self::ErrorType>> {
        self.bitmap.draw_circle(center, radius, style, fill)
    }

    fn fill_polygon<S: backend::BackendStyle, I: IntoIterator<Item = backend::BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), backend::DrawingErrorKind<Self::ErrorType>> {
        self.bitmap.fill_polygon(vert, style)
    }

    fn blit_bitmap(
        &mut self,
        pos: backend::BackendCoord,
        size: (u32, u32),
        src: &[u8],
    ) -> Result<(), backend::DrawingErrorKind<Self::ErrorType>> {
        self.bitmap.blit_bitmap(pos, size, src)
    }

    fn draw_text<S: backend::BackendTextStyle>(
        &mut self,
        text: &str,
        style: &S,
        pos: backend::BackendCoord,
    ) -> Result<(), backend::DrawingErrorKind<Self::ErrorType>> {
        use ab_glyph::{Font, ScaleFont};
        use backend::text_anchor::{HPos, VPos};
        let color = style.color();
        if color.alpha == 0.0 {
            return Ok(());
        }
        let font = &self.font;
        let units_per_em = font.units_per_em().unwrap_or(2048.0);
        let em = (style.size() / 1.24) as f32;
        let scaled = font.as_scaled(em * font.height_unscaled() / units_per_em);
        // The pen along the baseline, kerned; the glyphs relative to the text's start.
        let mut glyphs = Vec::with_capacity(text.len());
        let mut pen = 0.0_f32;
        let mut previous = None;
        for c in text.chars() {
            let id = scaled.glyph_id(c);
            if let Some(p) = previous {
                pen += scaled.kern(p, id);
            }
            glyphs.push((id, pen));
            pen += scaled.h_advance(id);
            previous = Some(id);
        }
        let dx = match style.anchor().h_pos {
            HPos::Left => 0.0,
            HPos::Center => -pen / 2.0,
            HPos::Right => -pen,
        };
        // The baseline below the anchor, as the SVG's `dy`: 0.76 em under a top anchor,
        // half an ex (the height of the x) under a centre, half an ex over a bottom.
        let ex = font.outline(font.glyph_id('x')).map_or(0.5 * em, |o| {
            o.bounds.min.y.max(o.bounds.max.y) / units_per_em * em
        });
        let baseline = match style.anchor().v_pos {
            VPos::Top => 0.76 * em,
            VPos::Center => 0.5 * ex,
            VPos::Bottom => -0.5 * ex,
        };
        // Rotated about the anchor, as the SVG's `rotate(…, x, y)`.
        let turn = style.transform();
        for (id, x) in glyphs {
            let glyph =
                id.with_scale_and_position(scaled.scale(), ab_glyph::point(dx + x, baseline));
            let Some(outline) = scaled.outline_glyph(glyph) else {
                continue;
            };
            let bounds = outline.px_bounds();
            // Whole pixels: px_bounds' corner is rounded outwards.
            let (left, top) = (bounds.min.x as i32, bounds.min.y as i32);
            let mut result = Ok(());
            outline.draw(|gx, gy, coverage| {
                let coverage = f64::from(coverage.clamp(0.0, 1.0));
                if coverage == 0.0 || result.is_err() {
                    return;
                }
                let (tx, ty) = turn.transform(left + gx as i32, top + gy as i32);
                let pixel = backend::BackendColor {
                    alpha: color.alpha * coverage,
                    rgb: color.rgb,
                };
                result = self.bitmap.draw_pixel((pos.0 + tx, pos.1 + ty), pixel);
            });
            result?;
        }
        Ok(())
    }
}

pub(super) type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// A part of the picture, on either backend.
pub(super) type Area<DB> = DrawingArea<DB, Shift>;

/// How a legend entry shows its series.
pub(super) enum Swatch {
    /// A line of this width.
    Line(RGBColor, u32),
    /// A dashed line.
    Dashed(RGBColor),
    /// A filled band.
    Band(RGBColor),
    /// A vertical line (an instant).
    Mark(RGBColor),
    /// A filled triangle.
    Triangle(RGBColor),
    /// A ring.
    Ring(RGBColor),
    /// Nothing: a line of text.
    None,
}

/// Draws a legend in its own column next to a panel, so that it never hides the data.
pub(super) fn legend<DB: DrawingBackend>(
    area: &Area<DB>,
    entries: &[(Swatch, String)],
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    // The panels' captions take the first ~35 px.
    let mut y = 52;
    for (swatch, text) in entries {
        let (x0, x1) = (10, 36);
        match *swatch {
            Swatch::Line(c, w) => {
                area.draw(&PathElement::new([(x0, y), (x1, y)], c.stroke_width(w)))?;
            }
            Swatch::Dashed(c) => {
                for x in (x0..x1).step_by(10) {
                    area.draw(&PathElement::new(
                        [(x, y), ((x + 6).min(x1), y)],
                        c.stroke_width(2),
                    ))?;
                }
            }
            Swatch::Band(c) => {
                area.draw(&Rectangle::new(
                    [(x0, y - 6), (x1, y + 6)],
                    c.mix(0.25).filled(),
                ))?;
            }
            Swatch::Mark(c) => {
                area.draw(&PathElement::new(
                    [((x0 + x1) / 2, y - 8), ((x0 + x1) / 2, y + 8)],
                    c.stroke_width(2),
                ))?;
            }
            Swatch::Triangle(c) => {
                area.draw(&TriangleMarker::new(((x0 + x1) / 2, y), 7, c.filled()))?;
            }
            Swatch::Ring(c) => {
                area.draw(&Circle::new(((x0 + x1) / 2, y), 6, c.stroke_width(2)))?;
            }
            Swatch::None => {}
        }
        area.draw(&Text::new(
            text.as_str(),
            (x1 + 8, y - 7),
            ("sans-serif", 13).into_font(),
        ))?;
        y += 22;
    }
    Ok(())
}

/// The width of the legend column, pixels.
pub(super) const LEGEND_W: u32 = 300;

/// The labels of a two-state line drawn at 0 (`off`) and 1 (`on`) on a secondary axis; no
/// label at the other ticks.
pub(super) fn two_state(off: &'static str, on: &'static str) -> impl Fn(&f64) -> String {
    move |v| {
        if v.abs() < 1e-9 {
            off.to_string()
        } else if (v - 1.0).abs() < 1e-9 {
            on.to_string()
        } else {
            String::new()
        }
    }
}

/// A tick label: 10 rather than 10.0, 0.25 as it is.
pub(super) fn tick(v: &f64) -> String {
    let r = (v * 1000.0).round() / 1000.0;
    format!("{}", if r == 0.0 { 0.0 } else { r })
}

/// A panel's chart with the common time axis: the same label areas in every panel, so that
/// their time axes line up.
pub(super) fn panel<'a, DB: DrawingBackend>(
    area: &'a Area<DB>,
    caption: &str,
) -> ChartBuilder<'a, 'a, DB> {
    let mut b = ChartBuilder::on(area);
    b.margin(10)
        .caption(caption, ("sans-serif", 18))
        .x_label_area_size(35)
        .y_label_area_size(70)
        .right_y_label_area_size(60);
    b
}
