/* chart.c: draws a pc_chart (log-log line chart or stacked bars, see chart.h) with cairo onto an
 * image surface (PNG) or an SVG surface; the drawing code is shared so both files show the same
 * chart. */
#include "chart.h"

#include <cairo-svg.h>
#include <cairo.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <unistd.h>

#include "file_replace.h"

/* Colour-blind-friendly qualitative palette (Okabe-Ito), cycled past its end. */
static const double palette[][3] = {
    {0.000, 0.447, 0.698}, {0.835, 0.369, 0.000}, {0.000, 0.620, 0.451}, {0.800, 0.475, 0.655},
    {0.902, 0.624, 0.000}, {0.337, 0.706, 0.914}, {0.941, 0.894, 0.259}, {0.000, 0.000, 0.000},
};
#define NPALETTE ((int)(sizeof palette / sizeof palette[0]))

typedef struct frame {
  double x0, y0, x1, y1;     /* plot area in device units (y0 top) */
  int dx_lo, dx_hi;          /* x axis spans decades 10^dx_lo .. 10^dx_hi */
  int dy_lo, dy_hi;
} frame;

static bool on_log_axis(double v) { return isfinite(v) && v > 0; }

static double map_x(const frame *f, double x) {
  return f->x0 + (log10(x) - f->dx_lo) / (f->dx_hi - f->dx_lo) * (f->x1 - f->x0);
}
static double map_y(const frame *f, double y) {
  return f->y1 - (log10(y) - f->dy_lo) / (f->dy_hi - f->dy_lo) * (f->y1 - f->y0);
}

/* Whole decades covering [lo, hi]; at least one decade so the axis is never degenerate. */
static void decades(double lo, double hi, int *dlo, int *dhi) {
  if (!(lo <= hi)) lo = hi = 1; /* no point: an empty 1..10 axis */
  *dlo = (int)floor(log10(lo));
  *dhi = (int)ceil(log10(hi));
  if (*dhi <= *dlo) *dhi = *dlo + 1;
}

static void set_font(cairo_t *cr, double size) {
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
}

/* Draws s with its anchor point at (x, y): ax, ay in {0, 0.5, 1} pick left/centre/right and
 * top/middle/baseline-ish bottom of the text's extents. */
static void text_at(cairo_t *cr, const char *s, double x, double y, double ax, double ay) {
  cairo_text_extents_t te;
  cairo_text_extents(cr, s, &te);
  cairo_move_to(cr, x - te.x_bearing - ax * te.width, y - te.y_bearing - ay * te.height);
  cairo_show_text(cr, s);
}

/* "10" with a superscript exponent, anchored like text_at. */
static void decade_label(cairo_t *cr, int k, double size, double x, double y, double ax, double ay) {
  char exp[16];
  snprintf(exp, sizeof exp, "%d", k);
  cairo_text_extents_t tb, te;
  set_font(cr, size);
  cairo_text_extents(cr, "10", &tb);
  set_font(cr, size * 0.7);
  cairo_text_extents(cr, exp, &te);
  double w = tb.x_advance + te.x_advance, h = tb.height + 0.45 * size;
  double left = x - ax * w, top = y - ay * h;
  set_font(cr, size);
  cairo_move_to(cr, left, top + h);
  cairo_show_text(cr, "10");
  set_font(cr, size * 0.7);
  cairo_move_to(cr, left + tb.x_advance, top + h - 0.5 * size);
  cairo_show_text(cr, exp);
}

static void draw_axes(cairo_t *cr, const frame *f, double fs) {
  int nx = f->dx_hi - f->dx_lo, ny = f->dy_hi - f->dy_lo;
  /* Label every decade up to ~8 of them, then every n-th so labels never overlap. */
  int stepx = nx > 8 ? (nx + 7) / 8 : 1, stepy = ny > 8 ? (ny + 7) / 8 : 1;
  cairo_set_line_width(cr, 1);
  for (int axis = 0; axis < 2; axis++) {
    int lo = axis ? f->dy_lo : f->dx_lo, hi = axis ? f->dy_hi : f->dx_hi, step = axis ? stepy : stepx;
    for (int k = lo; k <= hi; k++) {
      for (int m = 1; m <= 9; m++) {
        if (k == hi && m > 1) break;
        if (m > 1 && hi - lo > 6) continue; /* minor ticks only while they stay readable */
        double v = m * pow(10, k);
        double p = axis ? map_y(f, v) : map_x(f, v);
        double len = m == 1 ? 6 : 3;
        if (m == 1) { /* grid line */
          cairo_set_source_rgb(cr, 0.88, 0.88, 0.88);
          if (axis) { cairo_move_to(cr, f->x0, p); cairo_line_to(cr, f->x1, p); }
          else { cairo_move_to(cr, p, f->y0); cairo_line_to(cr, p, f->y1); }
          cairo_stroke(cr);
        }
        cairo_set_source_rgb(cr, 0, 0, 0);
        if (axis) { cairo_move_to(cr, f->x0, p); cairo_line_to(cr, f->x0 + len, p); }
        else { cairo_move_to(cr, p, f->y1); cairo_line_to(cr, p, f->y1 - len); }
        cairo_stroke(cr);
        if (m == 1 && (k - lo) % step == 0) {
          if (axis) decade_label(cr, k, fs, f->x0 - 6, p, 1, 0.5);
          else decade_label(cr, k, fs, p, f->y1 + 6, 0.5, 0);
        }
      }
    }
  }
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_rectangle(cr, f->x0, f->y0, f->x1 - f->x0, f->y1 - f->y0);
  cairo_stroke(cr);
}

/* The band between lo and hi, one polygon per stretch of points on the axes. */
static void draw_band(cairo_t *cr, const frame *f, const pc_chart_series *s, const double rgb[3]) {
  cairo_set_source_rgba(cr, rgb[0], rgb[1], rgb[2], 0.18);
  for (int i = 0; i < s->n;) {
    int j = i;
    while (j < s->n && on_log_axis(s->x[j]) && on_log_axis(s->lo[j]) && on_log_axis(s->hi[j])) j++;
    if (j - i >= 2) {
      cairo_move_to(cr, map_x(f, s->x[i]), map_y(f, s->hi[i]));
      for (int k = i + 1; k < j; k++) cairo_line_to(cr, map_x(f, s->x[k]), map_y(f, s->hi[k]));
      for (int k = j - 1; k >= i; k--) cairo_line_to(cr, map_x(f, s->x[k]), map_y(f, s->lo[k]));
      cairo_close_path(cr);
      cairo_fill(cr);
    }
    i = j > i ? j : i + 1;
  }
}

static void draw_series(cairo_t *cr, const frame *f, const pc_chart_series *s, const double rgb[3]) {
  if (s->lo && s->hi) draw_band(cr, f, s, rgb);
  cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
  cairo_set_line_width(cr, 2);
  bool pen_down = false;
  for (int i = 0; i < s->n; i++) {
    if (!on_log_axis(s->x[i]) || !on_log_axis(s->y[i])) {
      pen_down = false;
      continue;
    }
    double px = map_x(f, s->x[i]), py = map_y(f, s->y[i]);
    if (pen_down) cairo_line_to(cr, px, py);
    else cairo_move_to(cr, px, py);
    pen_down = true;
  }
  cairo_stroke(cr);
  for (int i = 0; i < s->n; i++) {
    if (!on_log_axis(s->x[i]) || !on_log_axis(s->y[i])) continue;
    cairo_new_sub_path(cr);
    cairo_arc(cr, map_x(f, s->x[i]), map_y(f, s->y[i]), 3, 0, 2 * M_PI);
  }
  cairo_fill(cr);
}

static void draw_legend(cairo_t *cr, const frame *f, const pc_chart *c, double fs) {
  if (c->nseries == 0) return;
  set_font(cr, fs);
  double wmax = 0;
  for (int i = 0; i < c->nseries; i++) {
    cairo_text_extents_t te;
    cairo_text_extents(cr, c->series[i].name ? c->series[i].name : "", &te);
    if (te.x_advance > wmax) wmax = te.x_advance;
  }
  double row = fs * 1.5, pad = fs * 0.6, swatch = fs * 2;
  double w = pad * 3 + swatch + wmax, h = pad * 2 + row * c->nseries;
  double x = f->x1 - w - 8, y = f->y0 + 8;
  cairo_rectangle(cr, x, y, w, h);
  cairo_set_source_rgba(cr, 1, 1, 1, 0.9);
  cairo_fill_preserve(cr);
  cairo_set_source_rgb(cr, 0.5, 0.5, 0.5);
  cairo_set_line_width(cr, 1);
  cairo_stroke(cr);
  for (int i = 0; i < c->nseries; i++) {
    const double *rgb = palette[i % NPALETTE];
    double cy = y + pad + row * (i + 0.5);
    cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
    cairo_set_line_width(cr, 2);
    cairo_move_to(cr, x + pad, cy);
    cairo_line_to(cr, x + pad + swatch, cy);
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    text_at(cr, c->series[i].name ? c->series[i].name : "", x + 2 * pad + swatch, cy, 0, 0.5);
  }
}

/* The bar chart's legend: a row of filled swatches under the title, so it never hides a bar. */
static void draw_bar_legend(cairo_t *cr, const pc_chart_bars *b, double x, double y, double fs) {
  set_font(cr, fs);
  for (int k = 0; k < b->nparts; k++) {
    const double *rgb = palette[k % NPALETTE];
    const char *name = b->parts[k] ? b->parts[k] : "";
    cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
    cairo_rectangle(cr, x, y - 0.45 * fs, fs * 0.9, fs * 0.9);
    cairo_fill(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    text_at(cr, name, x + fs * 1.3, y, 0, 0.5);
    cairo_text_extents_t te;
    cairo_text_extents(cr, name, &te);
    x += fs * 2.8 + te.x_advance;
  }
}

static void draw_bars(cairo_t *cr, const pc_chart *c, double fs) {
  const pc_chart_bars *b = c->bars;
  set_font(cr, fs);
  double label_w = 0;
  for (int r = 0; r < b->nrows; r++) {
    cairo_text_extents_t te;
    cairo_text_extents(cr, b->rows[r] ? b->rows[r] : "", &te);
    if (te.x_advance > label_w) label_w = te.x_advance;
  }
  double x0 = fs + label_w + fs * 0.8, x1 = c->width - fs * 2, y0 = fs * 4.5, y1 = c->height - fs * 4;
  double row = b->nrows ? (y1 - y0) / b->nrows : 0;
  cairo_set_line_width(cr, 1);
  for (int q = 0; q <= 4; q++) { /* grid and labels every 25% */
    double x = x0 + (x1 - x0) * q / 4.0;
    char label[8];
    snprintf(label, sizeof label, "%d%%", 25 * q);
    cairo_set_source_rgb(cr, 0.88, 0.88, 0.88);
    cairo_move_to(cr, x, y0);
    cairo_line_to(cr, x, y1);
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    text_at(cr, label, x, y1 + 6, 0.5, 0);
  }
  for (int r = 0; r < b->nrows; r++) {
    double top = y0 + row * (r + 0.15), h = row * 0.7, at = 0;
    for (int k = 0; k < b->nparts && at < 1; k++) {
      double v = fmin(b->value[(size_t)r * b->nparts + k], 1 - at);
      const double *rgb = palette[k % NPALETTE];
      cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
      cairo_rectangle(cr, x0 + (x1 - x0) * at, top, (x1 - x0) * v, h);
      cairo_fill(cr);
      at += v;
    }
    cairo_set_source_rgb(cr, 0, 0, 0);
    text_at(cr, b->rows[r] ? b->rows[r] : "", x0 - fs * 0.5, top + 0.5 * h, 1, 0.5);
  }
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_rectangle(cr, x0, y0, x1 - x0, y1 - y0);
  cairo_stroke(cr);
  draw_bar_legend(cr, b, x0, fs * 3, fs);
  set_font(cr, fs * 1.2);
  if (c->title) text_at(cr, c->title, 0.5 * c->width, fs * 1.2, 0.5, 0.5);
  set_font(cr, fs);
  if (c->x_label) text_at(cr, c->x_label, 0.5 * (x0 + x1), c->height - fs * 1.2, 0.5, 0.5);
}

static void draw(cairo_t *cr, const pc_chart *c) {
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  if (c->bars) { /* its height follows the bar count, so the font follows the width alone */
    draw_bars(cr, c, fmax(9, fmin(c->width, 560) / 40.0));
    return;
  }
  double fs = fmax(9, fmin(c->width, c->height) / 40.0);
  double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
  for (int s = 0; s < c->nseries; s++)
    for (int i = 0; i < c->series[s].n; i++) {
      double x = c->series[s].x[i], y = c->series[s].y[i];
      if (!on_log_axis(x) || !on_log_axis(y)) continue;
      xlo = fmin(xlo, x), xhi = fmax(xhi, x), ylo = fmin(ylo, y), yhi = fmax(yhi, y);
      if (c->series[s].lo && on_log_axis(c->series[s].lo[i])) ylo = fmin(ylo, c->series[s].lo[i]);
      if (c->series[s].hi && on_log_axis(c->series[s].hi[i])) yhi = fmax(yhi, c->series[s].hi[i]);
    }
  frame f = {.x0 = fs * 6, .y0 = fs * 3.5, .x1 = c->width - fs * 1.5, .y1 = c->height - fs * 5};
  decades(xlo, xhi, &f.dx_lo, &f.dx_hi);
  decades(ylo, yhi, &f.dy_lo, &f.dy_hi);

  set_font(cr, fs);
  draw_axes(cr, &f, fs);
  cairo_save(cr);
  cairo_rectangle(cr, f.x0, f.y0, f.x1 - f.x0, f.y1 - f.y0);
  cairo_clip(cr);
  for (int s = 0; s < c->nseries; s++) draw_series(cr, &f, &c->series[s], palette[s % NPALETTE]);
  cairo_restore(cr);
  draw_legend(cr, &f, c, fs);

  cairo_set_source_rgb(cr, 0, 0, 0);
  set_font(cr, fs * 1.2);
  if (c->title) text_at(cr, c->title, 0.5 * (f.x0 + f.x1), fs * 1.2, 0.5, 0.5);
  set_font(cr, fs);
  if (c->x_label) text_at(cr, c->x_label, 0.5 * (f.x0 + f.x1), c->height - fs * 1.5, 0.5, 0.5);
  if (c->y_label) {
    cairo_save(cr);
    cairo_translate(cr, fs * 1.2, 0.5 * (f.y0 + f.y1));
    cairo_rotate(cr, -M_PI / 2);
    text_at(cr, c->y_label, 0, 0, 0.5, 0.5);
    cairo_restore(cr);
  }
}

static int check_chart(const pc_chart *c, const char *path, pc_err *e) {
  if (!c || !path) return pc_errf(e, PC_EINVAL, "chart: NULL argument");
  if (c->width < PC_CHART_MIN_DIM || c->width > PC_CHART_MAX_DIM || c->height < PC_CHART_MIN_DIM ||
      c->height > PC_CHART_MAX_DIM)
    return pc_errf(e, PC_EINVAL, "%s: chart size %dx%d outside %d..%d", path, c->width, c->height, PC_CHART_MIN_DIM,
                   PC_CHART_MAX_DIM);
  if (c->bars) {
    const pc_chart_bars *b = c->bars;
    if (b->nrows < 0 || b->nrows > PC_CHART_MAX_BARS || b->nparts < 1 || b->nparts > PC_CHART_MAX_PARTS ||
        (b->nrows > 0 && (!b->rows || !b->value)) || !b->parts)
      return pc_errf(e, PC_EINVAL, "%s: bad bars (%d rows of %d parts; at most %d of %d)", path, b->nrows, b->nparts,
                     PC_CHART_MAX_BARS, PC_CHART_MAX_PARTS);
    for (int i = 0; i < b->nrows * b->nparts; i++)
      if (!(isfinite(b->value[i]) && b->value[i] >= 0))
        return pc_errf(e, PC_EINVAL, "%s: bar %d, part %d: value %g is not a fraction", path, i / b->nparts,
                       i % b->nparts, b->value[i]);
    return PC_OK;
  }
  if (c->nseries < 0 || (c->nseries > 0 && !c->series)) return pc_errf(e, PC_EINVAL, "%s: bad series list", path);
  for (int s = 0; s < c->nseries; s++)
    if (c->series[s].n < 0 || (c->series[s].n > 0 && (!c->series[s].x || !c->series[s].y)))
      return pc_errf(e, PC_EINVAL, "%s: series %d has no data", path, s);
    else if (!c->series[s].lo != !c->series[s].hi)
      return pc_errf(e, PC_EINVAL, "%s: series %d has half a band", path, s);
  return PC_OK;
}

static int cairo_fail(pc_err *e, const char *tmp, const char *path, cairo_status_t st) {
  unlink(tmp);
  return pc_errf(e, st == CAIRO_STATUS_NO_MEMORY ? PC_ENOMEM : PC_EIO, "%s: cannot draw the chart: %s", path,
                 cairo_status_to_string(st));
}

/* The chart drawn on surf; the drawing's status. */
static cairo_status_t draw_on(cairo_surface_t *surf, const pc_chart *c) {
  cairo_t *cr = cairo_create(surf);
  draw(cr, c);
  cairo_status_t st = cairo_status(cr);
  cairo_destroy(cr);
  return st;
}

/* Checks the chart and names the temporary file it is written to before the rename. */
static int begin(const pc_chart *c, const char *path, char *tmp, size_t tmp_size, pc_err *e) {
  int rc = check_chart(c, path, e);
  if (rc == PC_OK) rc = pc_file_tmp_path(path, tmp, tmp_size, e);
  return rc;
}

int pc_chart_write_png(const pc_chart *c, const char *path, pc_err *e) {
  char tmp[4096];
  int rc = begin(c, path, tmp, sizeof tmp, e);
  if (rc != PC_OK) return rc;
  cairo_surface_t *surf = cairo_image_surface_create(CAIRO_FORMAT_RGB24, c->width, c->height);
  cairo_status_t st = draw_on(surf, c);
  if (st == CAIRO_STATUS_SUCCESS) st = cairo_surface_write_to_png(surf, tmp);
  cairo_surface_destroy(surf);
  if (st != CAIRO_STATUS_SUCCESS) return cairo_fail(e, tmp, path, st);
  return pc_file_commit(tmp, path, e);
}

int pc_chart_write_svg(const pc_chart *c, const char *path, pc_err *e) {
  char tmp[4096];
  int rc = begin(c, path, tmp, sizeof tmp, e);
  if (rc != PC_OK) return rc;
  cairo_surface_t *surf = cairo_svg_surface_create(tmp, c->width, c->height);
  cairo_status_t st = draw_on(surf, c);
  cairo_surface_finish(surf); /* flushes the SVG to the file */
  if (st == CAIRO_STATUS_SUCCESS) st = cairo_surface_status(surf);
  cairo_surface_destroy(surf);
  if (st != CAIRO_STATUS_SUCCESS) return cairo_fail(e, tmp, path, st);
  return pc_file_commit(tmp, path, e);
}
