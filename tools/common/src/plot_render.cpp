// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: the --plot figure drawn with cairo (plot_render.hpp). The geometry comes from
// plot_layout.hpp; this file only turns it into strokes and text.
#include "tacse3/tools/plot_render.hpp"

#include <cairo-svg.h>
#include <cairo.h>
#include <fontconfig/fontconfig.h>

#include <cmath>
#include <memory>

namespace tacse3::tools::plot {

namespace {

constexpr double kFontSize = 11.0;
constexpr double kTitleSize = 14.0;

void set_colour(cairo_t* cr, Rgb c) {
  cairo_set_source_rgb(cr, c.r / 255.0, c.g / 255.0, c.b / 255.0);
}

Rgb colour_of(Role r) {
  switch (r) {
    case Role::kTruth:
      return kTruthColour;
    case Role::kEstimate:
      return kEstimateColour;
    case Role::kError:
      break;
  }
  return kErrorColour;
}

// The truth is drawn wider and first, so an estimate lying on it shows as a blue line inside an
// orange band instead of hiding it.
double width_of(Role r) {
  return r == Role::kTruth ? 3.0 : 1.4;
}

enum class Align { kLeft, kRight, kCentre };

void text(cairo_t* cr, double x, double y, const std::string& s, Align a = Align::kLeft) {
  cairo_text_extents_t e;
  cairo_text_extents(cr, s.c_str(), &e);
  if (a == Align::kRight) x -= e.x_advance;
  if (a == Align::kCentre) x -= e.x_advance / 2.0;
  cairo_move_to(cr, x, y);
  cairo_show_text(cr, s.c_str());
}

// One stroke per series: a new sub-path after every NaN.
void draw_series(cairo_t* cr, const Series& s, const std::vector<double>& t, const LinearMap& xm,
                 const LinearMap& ym) {
  bool pen_down = false;
  for (std::size_t i = 0; i < s.y.size() && i < t.size(); ++i) {
    if (!std::isfinite(s.y[i])) {
      pen_down = false;
      continue;
    }
    if (pen_down) {
      cairo_line_to(cr, xm(t[i]), ym(s.y[i]));
    } else {
      cairo_move_to(cr, xm(t[i]), ym(s.y[i]));
      pen_down = true;
    }
  }
  set_colour(cr, colour_of(s.role));
  cairo_set_line_width(cr, width_of(s.role));
  cairo_stroke(cr);
}

// A sample line per series, centred on a pixel row so a PNG shows its colour unblended.
void draw_legend(cairo_t* cr, const Panel& p, const Rect& r, double x) {
  double y = std::round(r.y) + 14.0;
  for (const Series& s : p.series) {
    cairo_move_to(cr, x, y - 3.5);
    cairo_line_to(cr, x + 22.0, y - 3.5);
    set_colour(cr, colour_of(s.role));
    cairo_set_line_width(cr, width_of(s.role));
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    text(cr, x + 28.0, y, s.label);
    y += 16.0;
  }
}

// Grid, frame and y tick labels; returns the panel's data-to-pixel y map.
LinearMap draw_axes(cairo_t* cr, const Panel& p, Range y, const Rect& r, const Ticks& xt,
                    const LinearMap& xm) {
  const Ticks yt = nice_ticks(y, 5);
  const LinearMap ym{yt.lo(), yt.hi(), r.y + r.h, r.y};
  cairo_set_line_width(cr, 1.0);
  cairo_set_source_rgb(cr, 0.88, 0.88, 0.88);
  for (const double v : yt.values) {
    cairo_move_to(cr, r.x, std::round(ym(v)) + 0.5);
    cairo_line_to(cr, r.x + r.w, std::round(ym(v)) + 0.5);
  }
  for (const double v : xt.values) {
    cairo_move_to(cr, std::round(xm(v)) + 0.5, r.y);
    cairo_line_to(cr, std::round(xm(v)) + 0.5, r.y + r.h);
  }
  cairo_stroke(cr);
  cairo_set_source_rgb(cr, 0.35, 0.35, 0.35);
  cairo_rectangle(cr, r.x + 0.5, r.y + 0.5, r.w - 1.0, r.h - 1.0);
  cairo_stroke(cr);
  cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
  for (const double v : yt.values)
    text(cr, r.x - 6.0, ym(v) + 4.0, tick_label(v, yt.decimals), Align::kRight);
  text(cr, r.x, r.y - 7.0, p.heading);
  return ym;
}

void draw_time_axis(cairo_t* cr, const Rect& r, const Ticks& xt, const LinearMap& xm) {
  cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
  for (const double v : xt.values) {
    text(cr, xm(v), r.y + r.h + 15.0, tick_label(v, xt.decimals), Align::kCentre);
  }
  text(cr, r.x + r.w / 2.0, r.y + r.h + 34.0, "time (s)", Align::kCentre);
}

void draw_figure(cairo_t* cr, const PlotData& d, const FigureLayout& f) {
  cairo_set_source_rgb(cr, 1.0, 1.0, 1.0);
  cairo_paint(cr);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
  cairo_set_font_size(cr, kTitleSize);
  cairo_set_source_rgb(cr, 0.0, 0.0, 0.0);
  text(cr, kLeftMargin, 22.0, d.title);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, kFontSize);
  if (!d.note.empty()) {
    set_colour(cr, kNoteColour);
    text(cr, kLeftMargin, 39.0, d.note);
  }
  if (f.panels.empty()) return;
  const Ticks xt = nice_ticks(finite_range({&d.t_s}), 10);
  const Rect& first = f.panels.front();
  const LinearMap xm{xt.lo(), xt.hi(), first.x, first.x + first.w};
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  const std::vector<Range> ys = panel_ranges(d);
  for (std::size_t i = 0; i < d.panels.size() && i < f.panels.size(); ++i) {
    const Rect& r = f.panels[i];
    const LinearMap ym = draw_axes(cr, d.panels[i], ys[i], r, xt, xm);
    cairo_save(cr);
    cairo_rectangle(cr, r.x, r.y, r.w, r.h);
    cairo_clip(cr);
    for (const Series& s : d.panels[i].series) draw_series(cr, s, d.t_s, xm, ym);
    cairo_restore(cr);
    draw_legend(cr, d.panels[i], r, f.legend_x);
  }
  draw_time_axis(cr, f.panels.back(), xt, xm);
}

cairo_status_t append(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

using Surface = std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)>;
using Context = std::unique_ptr<cairo_t, decltype(&cairo_destroy)>;

bool failed(cairo_status_t s, std::string* error) {
  if (s == CAIRO_STATUS_SUCCESS) return false;
  *error = std::string("cairo: ") + cairo_status_to_string(s);
  return true;
}

}  // namespace

bool render(const PlotData& d, Format format, std::string* out, std::string* error) {
  const FigureLayout f = figure_layout(d.panels.size());
  std::string bytes;
  Surface surface(
      format == Format::kSvg
          ? cairo_svg_surface_create_for_stream(append, &bytes, f.width, f.height)
          : cairo_image_surface_create(CAIRO_FORMAT_RGB24, static_cast<int>(std::ceil(f.width)),
                                       static_cast<int>(std::ceil(f.height))),
      cairo_surface_destroy);
  if (failed(cairo_surface_status(surface.get()), error)) return false;
  {
    Context cr(cairo_create(surface.get()), cairo_destroy);
    draw_figure(cr.get(), d, f);
    if (failed(cairo_status(cr.get()), error)) return false;
  }
  if (format == Format::kPng) {
    if (failed(cairo_surface_write_to_png_stream(surface.get(), append, &bytes), error)) {
      return false;
    }
  }
  cairo_surface_finish(surface.get());  // the SVG is written out here
  if (failed(cairo_surface_status(surface.get()), error)) return false;
  *out = std::move(bytes);
  return true;
}

void release_static_data() noexcept {
  cairo_debug_reset_static_data();
  FcFini();
}

}  // namespace tacse3::tools::plot
