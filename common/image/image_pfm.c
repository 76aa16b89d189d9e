/* image_pfm.c: the portable float map, which Mitsuba 0.6's bitmap reads as linear floats: "PF"
 * (RGB) or "Pf" (grey), width, height and a scale whose sign gives the byte order (negative:
 * little-endian) and whose magnitude multiplies every sample, then the rows from the bottom up.
 * No Debian library reads it, and the format is a header and an array. */
#include <ctype.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "file_read.h"
#include "image_internal.h"

/* The next whitespace-separated word of the header from *pos (at most cap - 1 bytes), leaving
 * *pos on the whitespace that ends it; false if the file ends first or the word is too long. */
static bool header_word(const unsigned char *b, size_t n, size_t *pos, char *word, size_t cap) {
  while (*pos < n && isspace(b[*pos])) ++*pos;
  size_t k = 0;
  while (*pos < n && !isspace(b[*pos])) {
    if (k + 1 >= cap) return false;
    word[k++] = (char)b[(*pos)++];
  }
  word[k] = 0;
  return k > 0 && *pos < n;
}

static bool parse_dim(const char *word, int *out) {
  char *end;
  long v = strtol(word, &end, 10);
  if (*end || v < 1 || v > PC_IMAGE_MAX_DIM) return false;
  *out = (int)v;
  return true;
}

static int decode(const char *path, const unsigned char *b, size_t n, pc_image *out, pc_err *e) {
  if (n < 3 || b[0] != 'P' || (b[1] != 'F' && b[1] != 'f') || !isspace(b[2]))
    return pc_errf(e, PC_EPARSE, "%s: not a PFM file (no 'PF' or 'Pf' line)", path);
  int channels = b[1] == 'F' ? 3 : 1, w, h;
  size_t pos = 2;
  char ws[32], hs[32], ss[32];
  if (!header_word(b, n, &pos, ws, sizeof ws) || !header_word(b, n, &pos, hs, sizeof hs) ||
      !header_word(b, n, &pos, ss, sizeof ss))
    return pc_errf(e, PC_EPARSE, "%s: PFM header cut short or malformed", path);
  if (!parse_dim(ws, &w) || !parse_dim(hs, &h))
    return pc_errf(e, PC_ELIMIT, "%s: PFM size '%s x %s' (1 to %d pixels a side)", path, ws, hs, PC_IMAGE_MAX_DIM);
  char *end;
  double scale = strtod(ss, &end);
  if (*end || !(scale != 0) || !isfinite(scale))
    return pc_errf(e, PC_EPARSE, "%s: PFM scale '%s' is not a finite non-zero number", path, ss);
  pos++; /* the one whitespace byte before the samples */
  size_t ns = (size_t)w * (size_t)h * (size_t)channels;
  if (n - pos < ns * 4)
    return pc_errf(e, PC_EPARSE, "%s: a %dx%d PFM needs %zu bytes of samples, the file has %zu (truncated)", path, w, h,
                   ns * 4, n - pos);
  out->rgb = malloc((size_t)w * (size_t)h * 3 * sizeof *out->rgb);
  if (!out->rgb) return pc_errf(e, PC_ENOMEM, "%s: out of memory for %dx%d pixels", path, w, h);
  bool little = scale < 0;
  float mag = (float)fabs(scale);
  const unsigned char *s = b + pos;
  for (int y = 0; y < h; y++) {
    /* the file's first row is the image's bottom one */
    float *row = out->rgb + (size_t)(h - 1 - y) * (size_t)w * 3;
    for (int x = 0; x < w; x++)
      for (int c = 0; c < channels; c++, s += 4) {
        uint32_t u = little ? (uint32_t)s[0] | (uint32_t)s[1] << 8 | (uint32_t)s[2] << 16 | (uint32_t)s[3] << 24
                            : (uint32_t)s[3] | (uint32_t)s[2] << 8 | (uint32_t)s[1] << 16 | (uint32_t)s[0] << 24;
        float v;
        memcpy(&v, &u, sizeof v);
        if (mag != 1.f) v *= mag;
        if (channels == 3) row[3 * x + c] = v;
        else row[3 * x] = row[3 * x + 1] = row[3 * x + 2] = v;
      }
  }
  out->w = w;
  out->h = h;
  return PC_OK;
}

int pc_pfm_read(const char *path, pc_image *out, pc_err *e) {
  char *file;
  size_t n;
  int rc = pc_file_read(path, (size_t)PC_IMAGE_MAX_DIM * PC_IMAGE_MAX_DIM * 12 + 4096, &file, &n, e);
  if (rc) return rc;
  rc = decode(path, (const unsigned char *)file, n, out, e);
  free(file);
  return rc;
}
