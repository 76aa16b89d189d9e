/* chart.h: small charts (cairo), written as PNG or SVG, with a title and a legend:
 * - a log-log line chart for convergence plots: error against time for a few series, decade
 *   ticks with labels on both axes. Points whose x or y is not positive and finite cannot sit
 *   on a log axis: they are left out and break the series' line there;
 * - a chart of horizontal stacked bars, each bar split into parts that are fractions of a
 *   whole (e.g. which strategies carry an image), on a linear 0..100% axis. */
#ifndef PC_CHART_H
#define PC_CHART_H

#include "error.h"

#define PC_CHART_MIN_DIM 64
#define PC_CHART_MAX_DIM 8192

typedef struct pc_chart_series {
  const char *name; /* legend entry */
  const double *x, *y;
  int n;
  const double *lo, *hi; /* optional (both or neither): a shaded band around y, e.g. the
                            spread of several runs; points where either is off the axis are
                            left out of it */
} pc_chart_series;

/* Stacked bars: row r's part k is value[r * nparts + k], a fraction in [0, 1] (parts drawn left
 * to right; a row's fractions should sum to at most 1, and what is past the axis is clipped). A
 * value that is not finite and >= 0 is refused. */
#define PC_CHART_MAX_BARS 256
#define PC_CHART_MAX_PARTS 8
typedef struct pc_chart_bars {
  const char *const *rows;  /* one label per bar, drawn top to bottom */
  const char *const *parts; /* the legend: one name (and colour) per part */
  const double *value;
  int nrows, nparts;
} pc_chart_bars;

typedef struct pc_chart {
  const char *title, *x_label, *y_label;
  int width, height; /* pixels (PNG) or points (SVG), PC_CHART_MIN_DIM..PC_CHART_MAX_DIM */
  const pc_chart_series *series; /* one colour each, in order */
  int nseries;
  const pc_chart_bars *bars; /* set: a bar chart (series and y_label are not used) */
} pc_chart;

/* Both write to a temporary file and rename it over path. */
int pc_chart_write_png(const pc_chart *c, const char *path, pc_err *e);
int pc_chart_write_svg(const pc_chart *c, const char *path, pc_err *e);

#endif
