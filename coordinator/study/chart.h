/* chart.h: a small log-log line chart (cairo) for convergence plots: error against time for a
 * few series, decade ticks with labels on both axes, a legend and a title; written as PNG or
 * SVG. Points whose x or y is not positive and finite cannot sit on a log axis: they are left
 * out and break the series' line there. */
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

typedef struct pc_chart {
  const char *title, *x_label, *y_label;
  int width, height; /* pixels (PNG) or points (SVG), PC_CHART_MIN_DIM..PC_CHART_MAX_DIM */
  const pc_chart_series *series; /* one colour each, in order */
  int nseries;
} pc_chart;

/* Both write to a temporary file and rename it over path. */
int pc_chart_write_png(const pc_chart *c, const char *path, pc_err *e);
int pc_chart_write_svg(const pc_chart *c, const char *path, pc_err *e);

#endif
