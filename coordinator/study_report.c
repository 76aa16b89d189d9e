/* study_report.c: the study's HTML report (see study_report.h). The charts are the SVG files
 * the study wrote, inlined as data: URIs rather than as <svg> elements, since cairo names its
 * glyphs alike in every file and inlined side by side they would collide. The noisiest region
 * is the window of the first method's image with the largest summed relative squared error
 * against the reference (without one, its estimated variance relative to its mean squared). */
#include "study_report.h"

#include <errno.h>
#include <math.h>
#include <sodium.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "file_read.h"
#include "image.h"
#include "metrics.h"

#define CROP_SIZE 256 /* pixels a crop is shown at (nearest-neighbour zoom) */

int pc_report_begin(pc_report *r, const char *path, pc_err *e) {
  memset(r, 0, sizeof *r);
  snprintf(r->path, sizeof r->path, "%s", path);
  snprintf(r->tmp, sizeof r->tmp, "%s.tmp.%ld", path, (long)getpid());
  if (!(r->f = fopen(r->tmp, "w"))) return pc_errf(e, PC_EIO, "%s: cannot create: %s", r->tmp, strerror(errno));
  fputs("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>pcbpt equal-time study</title>\n"
        "<style>\nbody{font-family:sans-serif;margin:2em;max-width:1400px}\n"
        "figure{display:inline-block;margin:0 1em 1em 0;vertical-align:top}\n"
        "figcaption{text-align:center;font-size:90%}\nimg.px{image-rendering:pixelated}\n"
        "pre{background:#f6f6f6;padding:1em;overflow-x:auto;font-size:85%}\n</style>\n</head>\n<body>\n"
        "<h1>pcbpt equal-time study</h1>\n"
        "<p>Every method rendered for the same time on the same farm workers, interleaved in short slices "
        "(docs/farm-study.md). Times are the farm's render seconds (summed worker-seconds / workers) unless said.</p>\n",
        r->f);
  return PC_OK;
}

static void html_text(FILE *f, const char *s) {
  for (; *s; s++) {
    if (*s == '<') fputs("&lt;", f);
    else if (*s == '>') fputs("&gt;", f);
    else if (*s == '&') fputs("&amp;", f);
    else if (*s == '"') fputs("&quot;", f);
    else fputc(*s, f);
  }
}

/* <img> with the file inlined; a missing file is an error (the study wrote it). */
static int inline_image(FILE *f, const char *path, const char *mime, const char *alt, const char *cls, int width, pc_err *e) {
  char *data = NULL;
  size_t n = 0;
  int rc = pc_file_read(path, 64u << 20, &data, &n, e);
  if (rc) return rc;
  size_t b64n = sodium_base64_ENCODED_LEN(n, sodium_base64_VARIANT_ORIGINAL);
  char *b64 = malloc(b64n);
  if (!b64) {
    free(data);
    return pc_errf(e, PC_ENOMEM, "out of memory for %s", path);
  }
  sodium_bin2base64(b64, b64n, (const unsigned char *)data, n, sodium_base64_VARIANT_ORIGINAL);
  fprintf(f, "<img%s%s%s alt=\"", cls ? " class=\"" : "", cls ? cls : "", cls ? "\"" : "");
  html_text(f, alt);
  if (width > 0) fprintf(f, "\" width=\"%d", width);
  fprintf(f, "\" src=\"data:%s;base64,%s\">", mime, b64);
  free(b64);
  free(data);
  return PC_OK;
}

static int figure(FILE *f, const char *dir, const char *leaf, const char *mime, const char *caption, const char *cls,
                  int width, pc_err *e) {
  char path[4400];
  snprintf(path, sizeof path, "%s/%s", dir, leaf);
  fputs("<figure>", f);
  int rc = inline_image(f, path, mime, caption, cls, width, e);
  fputs("<figcaption>", f);
  html_text(f, caption);
  fputs("</figcaption></figure>\n", f);
  return rc;
}

static const pc_image *beauty_of(const pc_exr_file *x) {
  for (int i = 0; i < x->nlayers; i++)
    if (x->names[i][0] == '\0') return &x->layers[i];
  return NULL;
}

static const pc_image *layer_of(const pc_exr_file *x, const char *name) {
  for (int i = 0; i < x->nlayers; i++)
    if (strcmp(x->names[i], name) == 0) return &x->layers[i];
  return NULL;
}

/* The top-left corner of the size x size window with the largest summed error. */
static void noisiest(const float *err, int w, int h, int size, int *bx, int *by) {
  double *sat = calloc((size_t)(w + 1) * (h + 1), sizeof *sat);
  *bx = *by = 0;
  if (!sat) return;
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++)
      sat[(size_t)(y + 1) * (w + 1) + x + 1] = err[(size_t)y * w + x] + sat[(size_t)y * (w + 1) + x + 1] +
                                               sat[(size_t)(y + 1) * (w + 1) + x] - sat[(size_t)y * (w + 1) + x];
  double best = -1;
  for (int y = 0; y + size <= h; y++)
    for (int x = 0; x + size <= w; x++) {
      double s = sat[(size_t)(y + size) * (w + 1) + x + size] - sat[(size_t)y * (w + 1) + x + size] -
                 sat[(size_t)(y + size) * (w + 1) + x] + sat[(size_t)y * (w + 1) + x];
      if (s > best) { best = s; *bx = x; *by = y; }
    }
  free(sat);
}

/* The window of rgb (w x h) at (x0, y0), zoomed to CROP_SIZE, as a PNG. */
static int write_crop(const char *path, const float *rgb, int w, int x0, int y0, int size, pc_err *e) {
  int z = CROP_SIZE / size > 0 ? CROP_SIZE / size : 1, n = size * z;
  float *out = malloc((size_t)n * n * 3 * sizeof *out);
  if (!out) return pc_errf(e, PC_ENOMEM, "out of memory for a crop");
  for (int y = 0; y < n; y++)
    for (int x = 0; x < n; x++)
      memcpy(&out[((size_t)y * n + x) * 3], &rgb[((size_t)(y0 + y / z) * w + x0 + x / z) * 3], 3 * sizeof(float));
  int rc = pc_png_write_preview(path, n, n, out, 0, e);
  free(out);
  return rc;
}

/* The crops of every method (and the reference) at the first method's noisiest window. */
static int crops(FILE *f, const pc_report_scene *s, pc_err *e) {
  pc_exr_file x[8] = {0};
  char path[4400];
  int rc = PC_OK, n = s->nmethods < 8 ? s->nmethods : 8;
  for (int m = 0; m < n && !rc; m++) {
    snprintf(path, sizeof path, "%s/%s.exr", s->dir, s->methods[m].name);
    rc = pc_exr_read_layers(path, &x[m], e);
    if (!rc && (!beauty_of(&x[m]) || x[m].w != s->w || x[m].h != s->h))
      rc = pc_errf(e, PC_EPARSE, "%s: no beauty, or not %dx%d", path, s->w, s->h);
  }
  int size = (s->w < s->h ? s->w : s->h) / 4;
  if (size < 1) size = 1;
  float *err = rc ? NULL : malloc((size_t)s->w * s->h * sizeof *err);
  if (!rc && !err) rc = pc_errf(e, PC_ENOMEM, "out of memory");
  int bx = 0, by = 0;
  if (!rc) {
    const float *a = beauty_of(&x[0])->rgb;
    const pc_image *var = layer_of(&x[0], "variance");
    for (size_t p = 0; p < (size_t)s->w * s->h; p++) {
      double sum = 0;
      for (int c = 0; c < 3; c++) {
        double v = a[p * 3 + c];
        if (s->reference) {
          double b = s->reference[p * 3 + c];
          sum += (v - b) * (v - b) / (b * b + PC_RELMSE_EPS);
        } else if (var) {
          sum += var->rgb[p * 3 + c] / (v * v + PC_RELMSE_EPS);
        }
      }
      err[p] = isfinite(sum) ? (float)sum : 0;
    }
    noisiest(err, s->w, s->h, size, &bx, &by);
    fprintf(f, "<h3>Zoomed crop of the noisiest region</h3>\n<p>%dx%d pixels at (%d, %d), where %s's %s is largest.</p>\n",
            size, size, bx, by, s->methods[0].name,
            s->reference ? "relative squared error against the reference" : "estimated relative variance");
  }
  for (int m = 0; m <= n && !rc; m++) {
    if (m == n && !s->reference) break;
    const char *name = m < n ? s->methods[m].name : "reference";
    char leaf[64];
    snprintf(leaf, sizeof leaf, "crop_%s.png", name);
    snprintf(path, sizeof path, "%s/%s", s->dir, leaf);
    rc = write_crop(path, m < n ? beauty_of(&x[m])->rgb : s->reference, s->w, bx, by, size, e);
    if (!rc) rc = figure(f, s->dir, leaf, "image/png", name, "px", 0, e);
  }
  free(err);
  for (int m = 0; m < n; m++) pc_exr_file_free(&x[m]);
  return rc;
}

int pc_report_add_scene(pc_report *r, const pc_report_scene *s, pc_err *e) {
  FILE *f = r->f;
  fputs("<section>\n<h2>", f);
  html_text(f, s->name);
  fputs("</h2>\n<p>Scene <code>", f);
  html_text(f, s->path);
  fprintf(f, "</code>, %dx%d.%s</p>\n<h3>Error against time</h3>\n", s->w, s->h,
          s->reference ? "" : " No reference: the errors are each image's own estimates (docs/variance.md).");
  int rc = figure(f, s->dir, "study_beauty.svg", "image/svg+xml", "beauty", NULL, 640, e);
  if (!rc && s->inner) rc = figure(f, s->dir, "study_inner.svg", "image/svg+xml", "inner strategies", NULL, 640, e);
  if (!rc && s->scaling) rc = figure(f, s->dir, "study_scaling.svg", "image/svg+xml", "scaling with the farm size", NULL, 640, e);
  if (!rc && s->shares) {
    fputs("<h3>Strategies carrying the final images</h3>\n", f);
    rc = figure(f, s->dir, "study_shares.svg", "image/svg+xml",
                "share of each image's mean luminance per strategy layer: where the light is, not where the error is",
                NULL, 640, e);
  }
  if (!rc && s->iterations) {
    fputs("<h3>Stability: the error of single iterations</h3>\n", f);
    rc = figure(f, s->dir, "study_iterations.svg", "image/svg+xml",
                "how often one iteration's error exceeds a multiple of the mean: a heavy tail (fireflies) reaches far right",
                NULL, 640, e);
  }
  if (!rc) fputs("<h3>Images at the end of the budget</h3>\n", f);
  for (int m = 0; m < s->nmethods && !rc; m++) {
    char leaf[64];
    snprintf(leaf, sizeof leaf, "%s.png", s->methods[m].name);
    rc = figure(f, s->dir, leaf, "image/png", s->methods[m].name, "px", s->w < 256 ? 256 : 0, e);
  }
  if (!rc && s->reference) {
    char path[4400];
    snprintf(path, sizeof path, "%s/reference.png", s->dir);
    rc = pc_png_write_preview(path, s->w, s->h, s->reference, 0, e);
    if (!rc) rc = figure(f, s->dir, "reference.png", "image/png", "reference", "px", s->w < 256 ? 256 : 0, e);
  }
  if (!rc) rc = crops(f, s, e);
  if (!rc) {
    fputs("<h3>Tables</h3>\n<pre>", f);
    html_text(f, s->tables);
    fputs("</pre>\n</section>\n", f);
  }
  return rc;
}

int pc_report_end(pc_report *r, pc_err *e) {
  fputs("</body>\n</html>\n", r->f);
  bool bad = ferror(r->f) != 0;
  if (fclose(r->f) != 0) bad = true;
  r->f = NULL;
  if (bad) {
    unlink(r->tmp);
    return pc_errf(e, PC_EIO, "%s: write error", r->path);
  }
  if (rename(r->tmp, r->path) != 0) {
    int err = errno;
    unlink(r->tmp);
    return pc_errf(e, PC_EIO, "%s: cannot rename into place: %s", r->path, strerror(err));
  }
  return PC_OK;
}

void pc_report_abandon(pc_report *r) {
  if (!r->f) return;
  fclose(r->f);
  r->f = NULL;
  unlink(r->tmp);
}
