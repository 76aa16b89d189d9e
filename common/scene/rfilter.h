/* rfilter.h: Mitsuba 0.6's reconstruction filters (box, tent, gaussian) as pixel measurement
 * functions. Pixel (x, y) of a W x H film measures the radiance through raster points p with the
 * separable weight f(p.x - x - 0.5) f(p.y - y - 0.5), f being Mitsuba's discretized filter (a step
 * function of MTS_FILTER_RESOLUTION = 31 steps per radius, normalized to integrate to 1), taken
 * over the film and divided by its integral there: that is what Mitsuba's weighted average of
 * filtered samples converges to, its edge pixels included. Eye samples are drawn from that
 * weight (filter importance sampling), so each still lands in one pixel with weight 1, and the
 * weight is their raster-area pdf; a light-tracing splat adds to every pixel whose weight at its
 * raster point is not zero. The box of radius 1/2 is the pixel itself: pcbpt's sampling as it
 * always was (pc_rfilter_is_pixel). */
#ifndef PC_RFILTER_H
#define PC_RFILTER_H

#include <math.h>
#include <stdbool.h>

#define PC_RFILTER_STEPS 31 /* Mitsuba's MTS_FILTER_RESOLUTION */
#define PC_RFILTER_MAX_RADIUS 4.f /* pixels: a splat reaches at most 9 x 9 pixels */

typedef enum { PC_RFILTER_BOX, PC_RFILTER_TENT, PC_RFILTER_GAUSSIAN } pc_rfilter_type;

typedef struct pc_rfilter {
  pc_rfilter_type type;
  float radius;                         /* in pixels */
  float step;                           /* radius / PC_RFILTER_STEPS */
  float scale;                          /* PC_RFILTER_STEPS / radius, as Mitsuba indexes its steps */
  /* the normalized steps across [-radius, radius] (step k covers [-radius + k step, + step),
   * every one > 0), the integral from -radius to each step's start, and 1 / (value * step) */
  float across[2 * PC_RFILTER_STEPS];
  float cdf[2 * PC_RFILTER_STEPS + 1];
  float inv_width[2 * PC_RFILTER_STEPS];
  unsigned char guide[64]; /* the step holding cdf total * g / 64: where the search starts */
} pc_rfilter;

/* Mitsuba's box of `radius` (its 1e-5 margin included), tent (radius 1) or gaussian of standard
 * deviation `param` (radius 4 stddev); param is ignored by the tent. Returns false for a radius
 * outside (0, PC_RFILTER_MAX_RADIUS] (or a step of value 0, which these filters never have). */
bool pc_rfilter_make(pc_rfilter *f, pc_rfilter_type type, float param);
/* Whether f is the pixel box (Mitsuba's box of radius 1/2, or a zeroed pc_rfilter), so that a
 * sample's pixel is the one it lies in. */
bool pc_rfilter_is_pixel(const pc_rfilter *f);

/* The 1-D filter at offset d from a pixel centre (not normalized to the film). */
static inline float pc_rfilter_value(const pc_rfilter *f, float d) {
  int i = (int)fabsf(d * f->scale); /* Mitsuba's index of |d|'s step */
  return i < PC_RFILTER_STEPS ? f->across[PC_RFILTER_STEPS + i] : 0.f;
}
float pc_rfilter_mass_cut(const pc_rfilter *f, float c, float extent);
/* The 1-D weight's integral over the film [0, extent] for the pixel centred at c. */
static inline float pc_rfilter_mass(const pc_rfilter *f, float c, float extent) {
  if (c - f->radius >= 0.f && c + f->radius <= extent) return f->cdf[2 * PC_RFILTER_STEPS];
  return pc_rfilter_mass_cut(f, c, extent);
}
/* Draws a raster coordinate for the pixel centred at c from its 1-D weight over [0, extent], u in
 * [0, 1); *pdf is that weight at the point (the filter over pc_rfilter_mass). */
float pc_rfilter_sample(const pc_rfilter *f, float c, float extent, float u, float *pdf);

#endif
