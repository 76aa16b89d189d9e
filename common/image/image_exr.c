/* image_exr.c: OpenEXR files through the OpenEXR Core C API: writing a render's layers and
 * metadata as one single-part FLOAT scanline file, and reading any scanline or tiled EXR's
 * RGB channel triplets (HALF, FLOAT or UINT) and simple header attributes. */
#include "image_internal.h"

#include "thread_pool.h"

#include <OpenEXR/openexr.h>
#include <pthread.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Where the library's error callback leaves the first (most specific) message; a write's
 * chunks are encoded on several threads, any of which may fail. */
typedef struct exr_msg {
  pthread_mutex_t mu;
  int have;
  char text[256];
} exr_msg;
#define EXR_MSG_INIT {.mu = PTHREAD_MUTEX_INITIALIZER}

static void on_exr_error(exr_const_context_t ctxt, exr_result_t code, const char *msg) {
  (void)code;
  void *ud = NULL;
  if (exr_get_user_data(ctxt, &ud) != EXR_ERR_SUCCESS || !ud) return;
  exr_msg *m = ud;
  pthread_mutex_lock(&m->mu);
  if (!m->have) {
    snprintf(m->text, sizeof m->text, "%s", msg ? msg : "");
    m->have = 1;
  }
  pthread_mutex_unlock(&m->mu);
}

static int exr_fail(pc_err *e, const char *path, const char *what, exr_result_t rv, exr_msg *m) {
  pthread_mutex_lock(&m->mu);
  int rc = pc_errf(e, rv == EXR_ERR_FILE_ACCESS ? PC_EIO : PC_EEXR, "%s: %s: %s", path, what,
                   m->have ? m->text : exr_get_default_error_message(rv));
  pthread_mutex_unlock(&m->mu);
  return rc;
}

static exr_context_initializer_t exr_init(exr_msg *m) {
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  init.error_handler_fn = on_exr_error;
  init.user_data = m;
  init.max_image_width = PC_IMAGE_MAX_DIM;
  init.max_image_height = PC_IMAGE_MAX_DIM;
  return init;
}

static char *dup_n(const char *s, size_t n) {
  char *d = malloc(n + 1);
  if (d) {
    memcpy(d, s, n);
    d[n] = '\0';
  }
  return d;
}

/* ------------------------------------------------------------------------------------------ */
/* Writing */

typedef struct out_channel {
  char name[272]; /* "<layer>.R": layer names up to 255 bytes plus the suffix */
  int layer, comp; /* its layer's band of interleaved rgb, and the component in it */
} out_channel;

static int cmp_channel(const void *a, const void *b) {
  return strcmp(((const out_channel *)a)->name, ((const out_channel *)b)->name);
}

static int check_layers(const char *path, const char *const *names, int nlayers, pc_err *e) {
  for (int i = 0; i < nlayers; i++) {
    if (!names[i]) return pc_errf(e, PC_EINVAL, "%s: layer %d has no name", path, i);
    if (strlen(names[i]) > 250)
      return pc_errf(e, PC_EINVAL, "%s: layer name '%.40s...' too long", path, names[i]);
    for (int j = 0; j < i; j++)
      if (strcmp(names[i], names[j]) == 0) return pc_errf(e, PC_EINVAL, "%s: layer '%s' given twice", path, names[i]);
  }
  return PC_OK;
}

/* The pixels are encoded a chunk at a time on every core (at most ENCODE_THREADS_MAX): filling
 * a chunk's rows from the caller's data and compressing them are independent between chunks,
 * and only the writes must follow the file's increasing line order, which each chunk's write
 * waits its turn for. The farm's final image is written while the render waits for it: a
 * 512x512 film's took 0.18 s on one thread. */
#define ENCODE_THREADS_MAX 16

/* One thread's band of rows and its encode pipeline. */
typedef struct exr_writer {
  float *rows;
  float **bands;
  exr_encode_pipeline_t enc;
  int inited;
  exr_result_t (*write_chunk)(exr_encode_pipeline_t *); /* the library's own write */
} exr_writer;

typedef struct encode_job {
  exr_context_t ctx;
  int part;
  const char *path;
  int w, h, lines, nch, nlayers;
  const out_channel *ch;
  pc_exr_rows_fn fill;
  void *user;
  exr_msg *m;
  exr_writer *writers;
  pthread_mutex_t mu;
  pthread_cond_t turn;
  int next; /* the chunk whose write is due */
  int rc;   /* the first failure, which ends every chunk's work and every wait */
  pc_err err;
} encode_job;

static void job_fail(encode_job *j, int rc, const pc_err *e) {
  pthread_mutex_lock(&j->mu);
  if (j->rc == PC_OK) {
    j->rc = rc;
    j->err = *e;
  }
  pthread_cond_broadcast(&j->turn);
  pthread_mutex_unlock(&j->mu);
}

static exr_result_t no_yield(exr_encode_pipeline_t *enc) {
  (void)enc;
  return EXR_ERR_SUCCESS;
}

/* The library's write of this chunk once every earlier chunk is written. */
static exr_result_t ordered_write(exr_encode_pipeline_t *enc) {
  encode_job *j = enc->encoding_user_data;
  exr_writer *wr = (exr_writer *)((char *)enc - offsetof(exr_writer, enc));
  pthread_mutex_lock(&j->mu);
  while (j->next != enc->chunk.idx && j->rc == PC_OK) pthread_cond_wait(&j->turn, &j->mu);
  bool failed = j->rc != PC_OK;
  pthread_mutex_unlock(&j->mu);
  if (failed) return EXR_ERR_INCORRECT_CHUNK; /* another chunk failed: the file is abandoned */
  exr_result_t rv = wr->write_chunk(enc);
  pthread_mutex_lock(&j->mu);
  j->next++;
  pthread_cond_broadcast(&j->turn);
  pthread_mutex_unlock(&j->mu);
  return rv;
}

static void encode_chunk(void *arg, int thread, int chunk) {
  encode_job *j = arg;
  exr_writer *wr = &j->writers[thread];
  pthread_mutex_lock(&j->mu);
  bool failed = j->rc != PC_OK;
  pthread_mutex_unlock(&j->mu);
  if (failed) return;
  int y = chunk * j->lines;
  pc_err e = {0};
  exr_chunk_info_t ci;
  exr_result_t rv = exr_write_scanline_chunk_info(j->ctx, j->part, y, &ci);
  if (!rv) rv = wr->inited ? exr_encoding_update(j->ctx, j->part, &ci, &wr->enc) : exr_encoding_initialize(j->ctx, j->part, &ci, &wr->enc);
  if (rv) {
    job_fail(j, exr_fail(&e, j->path, "cannot write pixels", rv, j->m), &e);
    return;
  }
  wr->inited = 1;
  int rc = j->fill(j->user, y, j->h - y < j->lines ? j->h - y : j->lines, wr->bands, &e);
  if (rc != PC_OK) {
    job_fail(j, rc, &e);
    return;
  }
  for (int c = 0; c < wr->enc.channel_count; c++) {
    exr_coding_channel_info_t *ec = &wr->enc.channels[c];
    const float *src = NULL;
    for (int k = 0; k < j->nch && !src; k++)
      if (strcmp(ec->channel_name, j->ch[k].name) == 0) src = wr->bands[j->ch[k].layer] + j->ch[k].comp;
    if (!src) {
      job_fail(j, pc_errf(&e, PC_EEXR, "%s: OpenEXR lost channel '%s'", j->path, ec->channel_name), &e);
      return;
    }
    ec->encode_from_ptr = (const uint8_t *)src;
    ec->user_pixel_stride = 3 * sizeof(float);
    ec->user_line_stride = 3 * sizeof(float) * j->w;
    ec->user_data_type = EXR_PIXEL_FLOAT;
    ec->user_bytes_per_element = sizeof(float);
  }
  rv = exr_encoding_choose_default_routines(j->ctx, j->part, &wr->enc);
  if (!rv) {
    wr->write_chunk = wr->enc.write_fn;
    wr->enc.write_fn = ordered_write;
    wr->enc.yield_until_ready_fn = no_yield;
    wr->enc.encoding_user_data = j;
    rv = exr_encoding_run(j->ctx, j->part, &wr->enc);
  }
  if (rv) job_fail(j, exr_fail(&e, j->path, "cannot write pixels", rv, j->m), &e);
}

/* Header and pixels into an open write context, the pixels asked of fill a chunk's band of
 * rows at a time; the caller finishes it. */
static int exr_encode(exr_context_t ctx, const char *path, int w, int h, out_channel *ch, int nch, int nlayers,
                      pc_exr_rows_fn fill, void *user, const pc_exr_attr *attrs, int nattrs, exr_msg *m, pc_err *e) {
  int part = 0;
  exr_result_t rv = exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, &part);
  /* RLE, not ZIP: noisy float radiance does not deflate, what compresses are the runs of
   * zeros in the strategy layers, and RLE finds those. Measured on renders' own images
   * (cornell-box 512x512 BDPT, 7 layers; ajar-door, outdoor, glossy-glass 256x256 PCBPT): ZIP
   * at deflate level 1 wrote in 0.65 / 0.13 / 0.17 / 0.15 s, RLE in 0.13 / 0.035 / 0.025 /
   * 0.038 s, for files 2-15% larger (19.4 MB against 19.0; 22.0 MB uncompressed). The farm
   * writes one at every checkpoint of the image and a render waits for its last one. */
  if (!rv) rv = exr_initialize_required_attr_simple(ctx, part, w, h, EXR_COMPRESSION_RLE);
  if (rv) return exr_fail(e, path, "cannot set up the header", rv, m);
  for (int c = 0; c < nch; c++) {
    if (strlen(ch[c].name) > 31 && (rv = exr_set_longname_support(ctx, 1)))
      return exr_fail(e, path, "cannot enable long channel names", rv, m);
    rv = exr_add_channel(ctx, part, ch[c].name, EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1,
                         1);
    if (rv) return exr_fail(e, path, "cannot add a channel", rv, m);
  }
  for (int i = 0; i < nattrs; i++) {
    if (!attrs[i].name || (attrs[i].type == PC_ATTR_STRING && !attrs[i].s))
      return pc_errf(e, PC_EINVAL, "%s: attribute %d has no name or no value", path, i);
    if (attrs[i].type == PC_ATTR_STRING)
      rv = exr_attr_set_string(ctx, part, attrs[i].name, attrs[i].s);
    else
      rv = exr_attr_set_double(ctx, part, attrs[i].name, attrs[i].d);
    if (rv) {
      char what[320];
      snprintf(what, sizeof what, "cannot set attribute '%.256s'", attrs[i].name);
      return exr_fail(e, path, what, rv, m);
    }
  }
  rv = exr_write_header(ctx);
  if (rv) return exr_fail(e, path, "cannot write the header", rv, m);

  int32_t lines = 1;
  rv = exr_get_scanlines_per_chunk(ctx, part, &lines);
  if (rv || lines < 1) return exr_fail(e, path, "cannot query the chunk size", rv, m);
  if (lines > h) lines = h; /* a short image's one chunk */
  int nchunks = (h + lines - 1) / lines, nwriters = pc_cpu_count();
  if (nwriters > ENCODE_THREADS_MAX) nwriters = ENCODE_THREADS_MAX;
  if (nwriters > nchunks) nwriters = nchunks;
  encode_job j = {.ctx = ctx, .part = part, .path = path, .w = w, .h = h, .lines = lines, .ch = ch, .nch = nch,
                  .nlayers = nlayers, .fill = fill, .user = user, .m = m};
  j.writers = calloc((size_t)nwriters, sizeof *j.writers);
  if (!j.writers) return pc_errf(e, PC_ENOMEM, "%s: out of memory for the writers", path);
  size_t band = (size_t)lines * (size_t)w * 3;
  int rc = PC_OK;
  for (int t = 0; t < nwriters && rc == PC_OK; t++) {
    exr_writer *wr = &j.writers[t];
    wr->rows = malloc(band * (size_t)nlayers * sizeof *wr->rows);
    wr->bands = malloc((size_t)nlayers * sizeof *wr->bands);
    if (!wr->rows || !wr->bands)
      rc = pc_errf(e, PC_ENOMEM, "%s: out of memory for %d rows of %d layers", path, lines, nlayers);
    else
      for (int l = 0; l < nlayers; l++) wr->bands[l] = wr->rows + band * (size_t)l;
  }
  if (rc == PC_OK && pthread_mutex_init(&j.mu, NULL) != 0) rc = pc_errf(e, PC_EIO, "%s: pthread_mutex_init failed", path);
  else if (rc == PC_OK && pthread_cond_init(&j.turn, NULL) != 0) {
    pthread_mutex_destroy(&j.mu);
    rc = pc_errf(e, PC_EIO, "%s: pthread_cond_init failed", path);
  }
  if (rc == PC_OK) {
    pc_pool_run_once(nwriters, nchunks, encode_chunk, &j);
    pthread_cond_destroy(&j.turn);
    pthread_mutex_destroy(&j.mu);
    rc = j.rc;
    if (rc != PC_OK && e) *e = j.err;
  }
  for (int t = 0; t < nwriters; t++) {
    exr_writer *wr = &j.writers[t];
    if (wr->inited) {
      exr_result_t drv = exr_encoding_destroy(ctx, &wr->enc);
      if (rc == PC_OK && drv) rc = exr_fail(e, path, "cannot write pixels", drv, m);
    }
    free(wr->rows);
    free(wr->bands);
  }
  free(j.writers);
  return rc;
}

int pc_exr_write_rows(const char *path, int w, int h, const char *const *names, int nlayers, pc_exr_rows_fn fill,
                      void *user, const pc_exr_attr *attrs, int nattrs, pc_err *e) {
  if (!path || !names || !fill || (!attrs && nattrs) || nlayers < 1 || nattrs < 0)
    return pc_errf(e, PC_EINVAL, "pc_exr_write: bad arguments");
  if (w <= 0 || h <= 0 || w > PC_IMAGE_MAX_DIM || h > PC_IMAGE_MAX_DIM)
    return pc_errf(e, PC_ELIMIT, "%s: EXR size %dx%d outside 1..%d", path, w, h, PC_IMAGE_MAX_DIM);
  int rc = check_layers(path, names, nlayers, e);
  if (rc) return rc;
  char tmp[4096];
  if ((rc = pc_file_tmp_path(path, tmp, sizeof tmp, e))) return rc;

  int nch = 3 * nlayers;
  out_channel *ch = calloc((size_t)nch, sizeof *ch);
  if (!ch) return pc_errf(e, PC_ENOMEM, "%s: out of memory", path);
  static const char comp[3] = {'R', 'G', 'B'};
  for (int i = 0; i < nlayers; i++) {
    for (int c = 0; c < 3; c++) {
      out_channel *o = &ch[3 * i + c];
      if (names[i][0]) snprintf(o->name, sizeof o->name, "%s.%c", names[i], comp[c]);
      else snprintf(o->name, sizeof o->name, "%c", comp[c]);
      o->layer = i;
      o->comp = c;
    }
  }
  /* EXR stores channel lists sorted by name. */
  qsort(ch, (size_t)nch, sizeof *ch, cmp_channel);

  exr_msg m = EXR_MSG_INIT;
  exr_context_initializer_t init = exr_init(&m);
  exr_context_t ctx = NULL;
  exr_result_t rv = exr_start_write(&ctx, tmp, EXR_WRITE_FILE_DIRECTLY, &init);
  if (rv) rc = exr_fail(e, tmp, "cannot create", rv, &m);
  else rc = exr_encode(ctx, path, w, h, ch, nch, nlayers, fill, user, attrs, nattrs, &m, e);
  if (ctx) {
    /* exr_finish writes the chunk offset table, so its failure is a failed write. */
    rv = exr_finish(&ctx);
    if (rv && rc == PC_OK) rc = exr_fail(e, tmp, "cannot finish", rv, &m);
  }
  free(ch);
  if (rc == PC_OK) return pc_file_commit(tmp, path, e);
  unlink(tmp);
  return rc;
}

/* pc_exr_write's bands: copies of the whole images' rows. */
typedef struct whole_images {
  int w, nlayers;
  const pc_exr_layer *layers;
} whole_images;

static int copy_rows(void *user, int y0, int ny, float *const *rows, pc_err *e) {
  (void)e;
  const whole_images *im = user;
  size_t row = (size_t)im->w * 3;
  for (int l = 0; l < im->nlayers; l++)
    memcpy(rows[l], im->layers[l].rgb + (size_t)y0 * row, (size_t)ny * row * sizeof(float));
  return PC_OK;
}

int pc_exr_write(const char *path, int w, int h, const pc_exr_layer *layers, int nlayers,
                 const pc_exr_attr *attrs, int nattrs, pc_err *e) {
  if (!path || !layers || nlayers < 1) return pc_errf(e, PC_EINVAL, "pc_exr_write: bad arguments");
  const char **names = calloc((size_t)nlayers, sizeof *names);
  if (!names) return pc_errf(e, PC_ENOMEM, "%s: out of memory", path);
  int rc = PC_OK;
  for (int i = 0; i < nlayers && rc == PC_OK; i++) {
    names[i] = layers[i].name;
    if (!layers[i].name || !layers[i].rgb) rc = pc_errf(e, PC_EINVAL, "%s: layer %d has no name or no pixels", path, i);
  }
  whole_images im = {w, nlayers, layers};
  if (rc == PC_OK) rc = pc_exr_write_rows(path, w, h, names, nlayers, copy_rows, &im, attrs, nattrs, e);
  free(names);
  return rc;
}

/* ------------------------------------------------------------------------------------------ */
/* Reading */

/* One candidate layer while scanning the channel list: its name is the channel name up to the
 * last '.', and chan[c] is the channel index of its R, G or B (-1 if absent). */
typedef struct in_layer {
  const char *name;
  int len;
  int chan[3];
} in_layer;

static int component_of(const char *suffix) {
  if (strcmp(suffix, "R") == 0) return 0;
  if (strcmp(suffix, "G") == 0) return 1;
  if (strcmp(suffix, "B") == 0) return 2;
  return -1;
}

/* Groups channels into complete R,G,B triplets: beauty first, then channel-list order. */
static int group_layers(const exr_attr_chlist_t *chl, in_layer *lay) {
  int n = 0;
  for (int i = 0; i < chl->num_channels; i++) {
    const exr_attr_chlist_entry_t *ce = &chl->entries[i];
    if (ce->x_sampling != 1 || ce->y_sampling != 1) continue;
    const char *name = ce->name.str;
    const char *dot = strrchr(name, '.');
    int len = dot ? (int)(dot - name) : 0;
    int c = component_of(dot ? dot + 1 : name);
    if (c < 0) continue;
    int k = 0;
    while (k < n && !(lay[k].len == len && strncmp(lay[k].name, name, (size_t)len) == 0)) k++;
    if (k == n) lay[n++] = (in_layer){name, len, {-1, -1, -1}};
    lay[k].chan[c] = i;
  }
  int kept = 0;
  for (int k = 0; k < n; k++)
    if (lay[k].chan[0] >= 0 && lay[k].chan[1] >= 0 && lay[k].chan[2] >= 0) lay[kept++] = lay[k];
  for (int k = 1; k < kept; k++)
    if (lay[k].len == 0) {
      in_layer beauty = lay[k];
      memmove(lay + 1, lay, sizeof *lay * (size_t)k);
      lay[0] = beauty;
    }
  return kept;
}

/* Part 0's chunks: its storage, data window and chunk size in pixels. */
typedef struct chunk_grid {
  exr_storage_t storage;
  exr_attr_box2i_t dw;
  int w, h;
  int32_t step_x, step_y;
} chunk_grid;

static int chunk_grid_of(exr_context_t ctx, const char *path, exr_storage_t storage, exr_attr_box2i_t dw,
                         chunk_grid *g, exr_msg *m, pc_err *e) {
  g->storage = storage;
  g->dw = dw;
  g->w = dw.max.x - dw.min.x + 1;
  g->h = dw.max.y - dw.min.y + 1;
  g->step_x = g->w;
  g->step_y = 1;
  exr_result_t rv;
  if (storage == EXR_STORAGE_TILED) rv = exr_get_tile_sizes(ctx, 0, 0, 0, &g->step_x, &g->step_y);
  else rv = exr_get_scanlines_per_chunk(ctx, 0, &g->step_y);
  if (rv || g->step_x < 1 || g->step_y < 1) return exr_fail(e, path, "bad chunk layout", rv, m);
  return PC_OK;
}

static exr_result_t chunk_info_at(exr_context_t ctx, const chunk_grid *g, int tx, int ty, exr_chunk_info_t *ci) {
  if (g->storage == EXR_STORAGE_TILED) return exr_read_tile_chunk_info(ctx, 0, tx, ty, 0, 0, ci);
  return exr_read_scanline_chunk_info(ctx, 0, g->dw.min.y + ty * g->step_y, ci);
}

/* Reads every chunk's offset and header before the layers are allocated: a header may claim
 * any data window up to PC_IMAGE_MAX_DIM squared, and a file that holds no chunks for it must
 * fail without an allocation of that size (fuzz_files met a 292-byte file claiming 3 GB). */
static int check_chunks(exr_context_t ctx, const char *path, const chunk_grid *g, exr_msg *m, pc_err *e) {
  exr_result_t rv = EXR_ERR_SUCCESS;
  for (int ty = 0; ty * (int64_t)g->step_y < g->h && !rv; ty++)
    for (int tx = 0; tx * (int64_t)g->step_x < g->w && !rv; tx++) {
      exr_chunk_info_t ci;
      rv = chunk_info_at(ctx, g, tx, ty, &ci);
    }
  if (rv) return exr_fail(e, path, "missing or bad pixel chunks", rv, m);
  return PC_OK;
}

/* Decodes every chunk of part 0, channel i into dst[i] (interleaved RGB, NULL = skip). */
static int exr_decode(exr_context_t ctx, const char *path, const chunk_grid *g, float **dst, int nchan,
                      exr_msg *m, pc_err *e) {
  int w = g->w, h = g->h;
  int32_t step_x = g->step_x, step_y = g->step_y;
  exr_attr_box2i_t dw = g->dw;
  exr_result_t rv = EXR_ERR_SUCCESS;
  const exr_attr_chlist_t *chl = NULL;
  if ((rv = exr_get_channels(ctx, 0, &chl))) return exr_fail(e, path, "no channel list", rv, m);
  exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
  int inited = 0, rc = PC_OK;
  for (int ty = 0; ty * (int64_t)step_y < h && !rv && !rc; ty++) {
    for (int tx = 0; tx * (int64_t)step_x < w && !rv && !rc; tx++) {
      exr_chunk_info_t ci;
      if ((rv = chunk_info_at(ctx, g, tx, ty, &ci))) break;
      rv = inited ? exr_decoding_update(ctx, 0, &ci, &dec)
                  : exr_decoding_initialize(ctx, 0, &ci, &dec);
      if (rv) break;
      inited = 1;
      /* For tiles the library reports tile indices in start_x/start_y, not pixels. */
      int64_t x0 = (int64_t)tx * step_x, y0 = (int64_t)ty * step_y;
      if (g->storage != EXR_STORAGE_TILED) {
        x0 = (int64_t)ci.start_x - dw.min.x;
        y0 = (int64_t)ci.start_y - dw.min.y;
      }
      if (x0 < 0 || y0 < 0 || x0 + ci.width > w || y0 + ci.height > h) {
        rc = pc_errf(e, PC_EEXR, "%s: chunk at (%lld,%lld) outside the data window", path,
                     (long long)x0, (long long)y0);
        break;
      }
      for (int c = 0; c < dec.channel_count; c++) {
        exr_coding_channel_info_t *dc = &dec.channels[c];
        float *base = NULL;
        for (int i = 0; i < nchan && !base; i++)
          if (dst[i] && strcmp(dc->channel_name, chl->entries[i].name.str) == 0) base = dst[i];
        dc->decode_to_ptr = base ? (uint8_t *)(base + ((size_t)y0 * w + (size_t)x0) * 3) : NULL;
        dc->user_pixel_stride = 3 * sizeof(float);
        dc->user_line_stride = 3 * sizeof(float) * w;
        dc->user_data_type = EXR_PIXEL_FLOAT;
        dc->user_bytes_per_element = sizeof(float);
      }
      rv = exr_decoding_choose_default_routines(ctx, 0, &dec);
      if (!rv) rv = exr_decoding_run(ctx, 0, &dec);
    }
  }
  if (inited) {
    exr_result_t drv = exr_decoding_destroy(ctx, &dec);
    if (!rv) rv = drv;
  }
  if (rc) return rc;
  if (rv) return exr_fail(e, path, "cannot read pixels", rv, m);
  return PC_OK;
}

/* string/double/int/float attributes as text; other types are skipped. */
static int collect_attrs(exr_context_t ctx, const char *path, pc_exr_file *out, exr_msg *m,
                         pc_err *e) {
  int32_t n = 0;
  exr_result_t rv = exr_get_attribute_count(ctx, 0, &n);
  if (rv || n < 0) return exr_fail(e, path, "cannot list attributes", rv, m);
  out->attr_names = calloc((size_t)n + 1, sizeof(char *));
  out->attr_values = calloc((size_t)n + 1, sizeof(char *));
  if (!out->attr_names || !out->attr_values)
    return pc_errf(e, PC_ENOMEM, "%s: out of memory", path);
  for (int32_t i = 0; i < n; i++) {
    const exr_attribute_t *a = NULL;
    rv = exr_get_attribute_by_index(ctx, 0, EXR_ATTR_LIST_FILE_ORDER, i, &a);
    if (rv) return exr_fail(e, path, "cannot read an attribute", rv, m);
    char num[64];
    const char *text = num;
    size_t len;
    switch (a->type) {
    case EXR_ATTR_STRING:
      text = a->string->str ? a->string->str : "";
      len = a->string->str && a->string->length > 0 ? (size_t)a->string->length : 0;
      break;
    case EXR_ATTR_DOUBLE:
      /* The shortest text that reads back as the same double. */
      snprintf(num, sizeof num, "%.15g", a->d);
      if (strtod(num, NULL) != a->d) snprintf(num, sizeof num, "%.17g", a->d);
      len = strlen(num);
      break;
    case EXR_ATTR_FLOAT:
      snprintf(num, sizeof num, "%.9g", (double)a->f);
      len = strlen(num);
      break;
    case EXR_ATTR_INT:
      snprintf(num, sizeof num, "%d", (int)a->i);
      len = strlen(num);
      break;
    default:
      continue;
    }
    int k = out->nattrs;
    out->attr_names[k] = dup_n(a->name, strlen(a->name));
    out->attr_values[k] = dup_n(text, len);
    out->nattrs++;
    if (!out->attr_names[k] || !out->attr_values[k])
      return pc_errf(e, PC_ENOMEM, "%s: out of memory", path);
  }
  return PC_OK;
}

/* What exr_read keeps: every layer or the beauty alone (the first triplet: group_layers puts
 * the unnamed one first), and the header's attributes or not. */
#define READ_BEAUTY_ONLY 1
#define READ_ATTRS 2
static int exr_read_part(exr_context_t ctx, const char *path, int what, pc_exr_file *out,
                         exr_msg *m, pc_err *e) {
  int nparts = 0;
  exr_storage_t storage;
  exr_attr_box2i_t dw;
  const exr_attr_chlist_t *chl = NULL;
  exr_result_t rv = exr_get_count(ctx, &nparts);
  if (!rv && nparts < 1) rv = EXR_ERR_FILE_BAD_HEADER;
  if (!rv) rv = exr_get_storage(ctx, 0, &storage);
  if (!rv) rv = exr_get_data_window(ctx, 0, &dw);
  if (!rv) rv = exr_get_channels(ctx, 0, &chl);
  if (rv || !chl) return exr_fail(e, path, "bad header", rv, m);
  if (storage != EXR_STORAGE_SCANLINE && storage != EXR_STORAGE_TILED)
    return pc_errf(e, PC_EUNSUPPORTED, "%s: deep EXR images are not supported", path);
  int64_t w = (int64_t)dw.max.x - dw.min.x + 1, h = (int64_t)dw.max.y - dw.min.y + 1;
  if (w < 1 || h < 1 || w > PC_IMAGE_MAX_DIM || h > PC_IMAGE_MAX_DIM)
    return pc_errf(e, PC_ELIMIT, "%s: EXR data window %lldx%lld outside 1..%d", path,
                   (long long)w, (long long)h, PC_IMAGE_MAX_DIM);
  out->w = (int)w;
  out->h = (int)h;
  chunk_grid grid;
  int rc = chunk_grid_of(ctx, path, storage, dw, &grid, m, e);
  if (!rc) rc = check_chunks(ctx, path, &grid, m, e);
  if (rc) return rc;

  int nchan = chl->num_channels;
  in_layer *lay = calloc((size_t)nchan + 1, sizeof *lay);
  float **dst = calloc((size_t)nchan + 1, sizeof *dst);
  if (!lay || !dst) {
    rc = pc_errf(e, PC_ENOMEM, "%s: out of memory", path);
    goto done;
  }
  int nl = group_layers(chl, lay);
  if (nl == 0) {
    rc = pc_errf(e, PC_EUNSUPPORTED, "%s: no R,G,B channel triplet", path);
    goto done;
  }
  if (what & READ_BEAUTY_ONLY) nl = 1;
  out->names = calloc((size_t)nl, sizeof *out->names);
  out->layers = calloc((size_t)nl, sizeof *out->layers);
  if (!out->names || !out->layers) {
    rc = pc_errf(e, PC_ENOMEM, "%s: out of memory", path);
    goto done;
  }
  for (int k = 0; k < nl; k++) {
    out->nlayers++;
    out->names[k] = dup_n(lay[k].name, (size_t)lay[k].len);
    out->layers[k].rgb = malloc(sizeof(float) * 3 * (size_t)w * (size_t)h);
    if (!out->names[k] || !out->layers[k].rgb) {
      rc = pc_errf(e, PC_ENOMEM, "%s: out of memory for %d layers of %lldx%lld", path, nl,
                   (long long)w, (long long)h);
      goto done;
    }
    out->layers[k].w = (int)w;
    out->layers[k].h = (int)h;
    for (int c = 0; c < 3; c++) dst[lay[k].chan[c]] = out->layers[k].rgb + c;
  }
  rc = exr_decode(ctx, path, &grid, dst, nchan, m, e);
  if (!rc && (what & READ_ATTRS)) rc = collect_attrs(ctx, path, out, m, e);
done:
  free(lay);
  free(dst);
  return rc;
}

static int exr_read(const char *path, int what, pc_exr_file *out, pc_err *e) {
  memset(out, 0, sizeof *out);
  exr_msg m = EXR_MSG_INIT;
  exr_context_initializer_t init = exr_init(&m);
  exr_context_t ctx = NULL;
  exr_result_t rv = exr_start_read(&ctx, path, &init);
  int rc;
  if (rv) rc = exr_fail(e, path, rv == EXR_ERR_FILE_ACCESS ? "cannot open" : "bad header", rv, &m);
  else rc = exr_read_part(ctx, path, what, out, &m, e);
  if (ctx) exr_finish(&ctx); /* a read context has nothing left to flush */
  if (rc) pc_exr_file_free(out);
  return rc;
}

int pc_exr_read_layers(const char *path, pc_exr_file *out, pc_err *e) {
  if (!path || !out) return pc_errf(e, PC_EINVAL, "pc_exr_read_layers: NULL argument");
  return exr_read(path, READ_ATTRS, out, e);
}

int pc_exr_read_beauty_attrs(const char *path, pc_exr_file *out, pc_err *e) {
  if (!path || !out) return pc_errf(e, PC_EINVAL, "pc_exr_read_beauty_attrs: NULL argument");
  return exr_read(path, READ_BEAUTY_ONLY | READ_ATTRS, out, e);
}

int pc_exr_read_beauty(const char *path, pc_image *out, pc_err *e) {
  pc_exr_file f;
  int rc = exr_read(path, READ_BEAUTY_ONLY, &f, e);
  if (rc) return rc;
  *out = f.layers[0];
  f.layers[0].rgb = NULL;
  pc_exr_file_free(&f);
  return PC_OK;
}

const char *pc_exr_attr_get(const pc_exr_file *f, const char *name) {
  for (int i = 0; i < f->nattrs; i++)
    if (strcmp(f->attr_names[i], name) == 0) return f->attr_values[i];
  return NULL;
}

void pc_exr_file_free(pc_exr_file *f) {
  if (!f) return;
  for (int i = 0; i < f->nlayers; i++) {
    if (f->names) free(f->names[i]);
    if (f->layers) pc_image_free(&f->layers[i]);
  }
  for (int i = 0; i < f->nattrs; i++) {
    free(f->attr_names[i]);
    free(f->attr_values[i]);
  }
  free(f->names);
  free(f->layers);
  free(f->attr_names);
  free(f->attr_values);
  memset(f, 0, sizeof *f);
}
