/* test_image.c: image files (EXR/PNG/JPEG read and write, untrusted-input errors) and the
 * image metrics. Every file goes into a fresh mkdtemp directory. */
#include <setjmp.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <pthread.h>
#include <string.h>

#include <cmocka.h>

#include <OpenEXR/openexr.h>
#include <dirent.h>
#include <jpeglib.h>
#include <math.h>
#include <png.h>
#include <unistd.h>
#include <zlib.h>

#include <stb_image_write.h>

#include "image.h"
#include "metrics.h"

typedef struct fixture {
  char dir[256];
} fixture;

static int setup(void **state) {
  fixture *fx = calloc(1, sizeof *fx);
  if (!fx) return -1;
  snprintf(fx->dir, sizeof fx->dir, "%s/pcbpt_test_image_XXXXXX",
           getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
  if (!mkdtemp(fx->dir)) return -1;
  *state = fx;
  return 0;
}

static int teardown(void **state) {
  fixture *fx = *state;
  DIR *d = opendir(fx->dir);
  if (d) {
    struct dirent *de;
    char p[512];
    while ((de = readdir(d)))
      if (strcmp(de->d_name, ".") && strcmp(de->d_name, "..")) {
        snprintf(p, sizeof p, "%s/%s", fx->dir, de->d_name);
        unlink(p);
      }
    closedir(d);
  }
  rmdir(fx->dir);
  free(fx);
  return 0;
}

static const char *path_in(void **state, const char *name) {
  static char buf[8][512];
  static int next;
  char *p = buf[next++ % 8];
  snprintf(p, 512, "%s/%s", ((fixture *)*state)->dir, name);
  return p;
}

static int no_temp_files(void **state) {
  DIR *d = opendir(((fixture *)*state)->dir);
  if (!d) return 0;
  int ok = 1;
  struct dirent *de;
  while ((de = readdir(d)))
    if (strstr(de->d_name, ".tmp.")) ok = 0;
  closedir(d);
  return ok;
}

static unsigned char *slurp(const char *path, size_t *n) {
  FILE *f = fopen(path, "rb");
  assert_non_null(f);
  fseek(f, 0, SEEK_END);
  long sz = ftell(f);
  fseek(f, 0, SEEK_SET);
  unsigned char *b = malloc((size_t)sz);
  assert_non_null(b);
  assert_int_equal(fread(b, 1, (size_t)sz, f), (size_t)sz);
  fclose(f);
  *n = (size_t)sz;
  return b;
}

static void spit(const char *path, const void *b, size_t n) {
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  assert_int_equal(fwrite(b, 1, n, f), n);
  assert_int_equal(fclose(f), 0);
}

static float *pattern(int w, int h, float seed) {
  float *p = malloc(sizeof(float) * 3 * (size_t)w * h);
  assert_non_null(p);
  for (int i = 0; i < w * h * 3; i++) p[i] = seed * (float)(i % 97) - 3.0f + 1e-7f * (float)i;
  p[0] = -0.0f;
  p[1] = 1e-40f; /* denormal */
  p[2] = 3.4e38f;
  return p;
}

/* Expects a failing read to leave no image and give a message. */
static void expect_read_fails(const char *path) {
  pc_image img = {.w = 7, .h = 7, .rgb = (float *)&img};
  pc_err e = {0};
  int rc = pc_image_read(path, 1, &img, &e);
  assert_true(rc < 0);
  assert_int_equal(e.code, rc);
  assert_true(e.msg[0] != '\0');
  assert_null(img.rgb);
}

/* ---------------------------------------------------------------------------------------- */
/* EXR */

static const char *find_attr(const pc_exr_file *f, const char *name) {
  for (int i = 0; i < f->nattrs; i++)
    if (strcmp(f->attr_names[i], name) == 0) return f->attr_values[i];
  return NULL;
}

static void test_exr_roundtrip(void **state) {
  const int w = 37, h = 23;
  float *px[4];
  const char *names[4] = {"pt", "", "s2t3", "lt"};
  pc_exr_layer layers[4];
  for (int i = 0; i < 4; i++) {
    px[i] = pattern(w, h, 0.37f * (float)(i + 1));
    layers[i] = (pc_exr_layer){names[i], px[i]};
  }
  pc_exr_attr attrs[] = {
      {.name = "pcbpt.scene", .type = PC_ATTR_STRING, .s = "cbox.xml"},
      {.name = "pcbpt.seconds", .type = PC_ATTR_DOUBLE, .d = 12.5},
      {.name = "pcbpt.light_paths", .type = PC_ATTR_DOUBLE, .d = 12345678901.0},
      {.name = "pcbpt.tenth", .type = PC_ATTR_DOUBLE, .d = 0.1},
      {.name = "pcbpt.method", .type = PC_ATTR_STRING, .s = "pcbpt with spaces"},
  };
  const char *path = path_in(state, "rt.exr");
  pc_err e = {0};
  assert_int_equal(pc_exr_write(path, w, h, layers, 4, attrs, 5, &e), PC_OK);
  assert_true(no_temp_files(state));

  pc_exr_file f;
  assert_int_equal(pc_exr_read_layers(path, &f, &e), PC_OK);
  assert_int_equal(f.w, w);
  assert_int_equal(f.h, h);
  assert_int_equal(f.nlayers, 4);
  assert_string_equal(f.names[0], ""); /* beauty first */
  for (int i = 0; i < 4; i++) {
    int k = 0;
    while (k < f.nlayers && strcmp(f.names[k], names[i]) != 0) k++;
    assert_true(k < f.nlayers);
    assert_int_equal(f.layers[k].w, w);
    assert_int_equal(f.layers[k].h, h);
    assert_memory_equal(f.layers[k].rgb, px[i], sizeof(float) * 3 * w * h);
  }
  assert_string_equal(find_attr(&f, "pcbpt.scene"), "cbox.xml");
  assert_string_equal(find_attr(&f, "pcbpt.method"), "pcbpt with spaces");
  assert_string_equal(find_attr(&f, "pcbpt.seconds"), "12.5");
  assert_string_equal(find_attr(&f, "pcbpt.light_paths"), "12345678901");
  assert_true(strtod(find_attr(&f, "pcbpt.tenth"), NULL) == 0.1);
  pc_exr_file_free(&f);

  /* the beauty alone, with every attribute (what render's summary and preview read) */
  assert_int_equal(pc_exr_read_beauty_attrs(path, &f, &e), PC_OK);
  assert_int_equal(f.nlayers, 1);
  assert_string_equal(f.names[0], "");
  assert_memory_equal(f.layers[0].rgb, px[1], sizeof(float) * 3 * w * h);
  assert_string_equal(find_attr(&f, "pcbpt.method"), "pcbpt with spaces");
  assert_string_equal(find_attr(&f, "pcbpt.light_paths"), "12345678901");
  pc_exr_file_free(&f);

  pc_image img;
  assert_int_equal(pc_image_read(path, 1, &img, &e), PC_OK);
  assert_int_equal(img.w, w);
  assert_int_equal(img.h, h);
  assert_memory_equal(img.rgb, px[1], sizeof(float) * 3 * w * h);
  pc_image_free(&img);
  for (int i = 0; i < 4; i++) free(px[i]);
}

static void test_exr_no_beauty_gives_first_triplet(void **state) {
  float *a = pattern(5, 3, 1.0f), *b = pattern(5, 3, 2.0f);
  pc_exr_layer layers[] = {{"zeta", a}, {"alpha", b}};
  const char *path = path_in(state, "nb.exr");
  pc_err e;
  assert_int_equal(pc_exr_write(path, 5, 3, layers, 2, NULL, 0, &e), PC_OK);
  pc_image img;
  assert_int_equal(pc_image_read(path, 0, &img, &e), PC_OK);
  assert_memory_equal(img.rgb, b, sizeof(float) * 45); /* "alpha.*" sorts first */
  pc_image_free(&img);
  free(a);
  free(b);
}

static void test_exr_write_errors(void **state) {
  float *a = pattern(4, 4, 1.0f);
  pc_exr_layer dup[] = {{"x", a}, {"x", a}};
  pc_err e = {0};
  assert_int_equal(pc_exr_write(path_in(state, "d.exr"), 4, 4, dup, 2, NULL, 0, &e), PC_EINVAL);
  assert_int_equal(pc_exr_write(path_in(state, "z.exr"), 0, 4, dup, 1, NULL, 0, &e), PC_ELIMIT);
  assert_int_equal(pc_exr_write(path_in(state, "nodir/x.exr"), 4, 4, dup, 1, NULL, 0, &e), PC_EIO);
  /* "compression" is a required attribute of another type: the library must refuse it. */
  pc_exr_attr bad = {.name = "compression", .type = PC_ATTR_STRING, .s = "zip"};
  assert_true(pc_exr_write(path_in(state, "c.exr"), 4, 4, dup, 1, &bad, 1, &e) < 0);
  assert_true(no_temp_files(state));
  free(a);
}

/* pc_exr_write_rows asks for every row once (bands on several threads at once, in any order)
 * and writes what it is given; a fill that fails ends the write with its error and leaves no
 * file. */
typedef struct band_log {
  int w, fail_row;
  pthread_mutex_t mu;
  int asked[300]; /* times each row was asked for */
} band_log;

static int fill_pattern(void *user, int y0, int ny, float *const *rows, pc_err *e) {
  band_log *b = user;
  if (y0 < 0 || ny < 1 || y0 + ny > 300) return pc_errf(e, PC_EINVAL, "band at row %d (%d rows)", y0, ny);
  pthread_mutex_lock(&b->mu);
  for (int y = y0; y < y0 + ny; y++) b->asked[y]++;
  pthread_mutex_unlock(&b->mu);
  if (y0 <= b->fail_row && b->fail_row < y0 + ny) return pc_errf(e, PC_EIO, "fill failed on purpose");
  for (int l = 0; l < 2; l++)
    for (int i = 0; i < ny * b->w * 3; i++) rows[l][i] = (float)(l * 1000 + y0 * b->w * 3 + i);
  return PC_OK;
}

static void test_exr_write_rows(void **state) {
  enum { W = 7, H = 300 }; /* more rows than any compression's chunk */
  const char *names[] = {"", "other"};
  const char *path = path_in(state, "rows.exr");
  band_log b = {.w = W, .fail_row = -1, .mu = PTHREAD_MUTEX_INITIALIZER};
  pc_err e = {0};
  assert_int_equal(pc_exr_write_rows(path, W, H, names, 2, fill_pattern, &b, NULL, 0, &e), PC_OK);
  for (int y = 0; y < H; y++) assert_int_equal(b.asked[y], 1);
  pc_exr_file f;
  assert_int_equal(pc_exr_read_layers(path, &f, &e), PC_OK);
  assert_int_equal(f.nlayers, 2);
  for (int l = 0; l < 2; l++) {
    int k = strcmp(f.names[l], "other") == 0 ? 1 : 0;
    for (int i = 0; i < W * H * 3; i++) assert_true(f.layers[l].rgb[i] == (float)(k * 1000 + i));
  }
  pc_exr_file_free(&f);
  band_log bad = {.w = W, .fail_row = 150, .mu = PTHREAD_MUTEX_INITIALIZER};
  assert_int_equal(pc_exr_write_rows(path_in(state, "fail.exr"), W, H, names, 2, fill_pattern, &bad, NULL, 0, &e), PC_EIO);
  assert_non_null(strstr(e.msg, "on purpose"));
  assert_int_equal(access(path_in(state, "fail.exr"), F_OK), -1);
  assert_true(no_temp_files(state));
}

/* Writes channels of one pixel type with the Core API, as other software would. data[c] is a
 * planar w*h array of that type for channel c. */
static void write_raw_exr_at(const char *path, int ox, int oy, int w, int h,
                             exr_storage_t storage, exr_pixel_type_t type, const char **names,
                             int nch, void **data) {
  int bpe = type == EXR_PIXEL_HALF ? 2 : 4;
  exr_context_t ctx;
  int part;
  assert_int_equal(exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, NULL), 0);
  assert_int_equal(exr_add_part(ctx, NULL, storage, &part), 0);
  assert_int_equal(exr_initialize_required_attr_simple(ctx, part, w, h, EXR_COMPRESSION_ZIPS), 0);
  exr_attr_box2i_t dw;
  dw.min.x = ox;
  dw.min.y = oy;
  dw.max.x = ox + w - 1;
  dw.max.y = oy + h - 1;
  assert_int_equal(exr_set_data_window(ctx, part, &dw), 0);
  if (storage == EXR_STORAGE_TILED)
    assert_int_equal(
        exr_set_tile_descriptor(ctx, part, 8, 8, EXR_TILE_ONE_LEVEL, EXR_TILE_ROUND_DOWN), 0);
  for (int c = 0; c < nch; c++)
    assert_int_equal(
        exr_add_channel(ctx, part, names[c], type, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1), 0);
  assert_int_equal(exr_attr_set_int(ctx, part, "someint", -42), 0);
  assert_int_equal(exr_attr_set_float(ctx, part, "somefloat", 0.25f), 0);
  assert_int_equal(exr_write_header(ctx), 0);
  exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
  int first = 1;
  int tw = storage == EXR_STORAGE_TILED ? 8 : w, th = storage == EXR_STORAGE_TILED ? 8 : 1;
  for (int ty = 0; ty * th < h; ty++)
    for (int tx = 0; tx * tw < w; tx++) {
      exr_chunk_info_t ci;
      if (storage == EXR_STORAGE_TILED)
        assert_int_equal(exr_write_tile_chunk_info(ctx, part, tx, ty, 0, 0, &ci), 0);
      else
        assert_int_equal(exr_write_scanline_chunk_info(ctx, part, oy + ty, &ci), 0);
      if (first) assert_int_equal(exr_encoding_initialize(ctx, part, &ci, &enc), 0);
      else assert_int_equal(exr_encoding_update(ctx, part, &ci, &enc), 0);
      first = 0;
      for (int c = 0; c < enc.channel_count; c++) {
        int k = 0;
        while (strcmp(names[k], enc.channels[c].channel_name) != 0) k++;
        enc.channels[c].encode_from_ptr =
            (const uint8_t *)data[k] + ((size_t)ty * th * w + (size_t)tx * tw) * bpe;
        enc.channels[c].user_pixel_stride = bpe;
        enc.channels[c].user_line_stride = bpe * w;
        enc.channels[c].user_data_type = type;
        enc.channels[c].user_bytes_per_element = bpe;
      }
      assert_int_equal(exr_encoding_choose_default_routines(ctx, part, &enc), 0);
      assert_int_equal(exr_encoding_run(ctx, part, &enc), 0);
    }
  assert_int_equal(exr_encoding_destroy(ctx, &enc), 0);
  assert_int_equal(exr_finish(&ctx), 0);
}

static void write_raw_exr(const char *path, int w, int h, exr_storage_t storage,
                          exr_pixel_type_t type, const char **names, int nch, void **data) {
  write_raw_exr_at(path, 0, 0, w, h, storage, type, names, nch, data);
}

static void test_exr_half_uint_tiled(void **state) {
  const int w = 19, h = 11;
  /* HALF bit patterns of exactly representable values. */
  static const uint16_t hv[4] = {0x3800, 0x3c00, 0x4000, 0xb400}; /* 0.5 1 2 -0.25 */
  static const float hf[4] = {0.5f, 1.0f, 2.0f, -0.25f};
  uint16_t *half[3];
  uint32_t *uin[3];
  float *flt[3];
  for (int c = 0; c < 3; c++) {
    half[c] = malloc(sizeof(uint16_t) * w * h);
    uin[c] = malloc(sizeof(uint32_t) * w * h);
    flt[c] = malloc(sizeof(float) * w * h);
    for (int i = 0; i < w * h; i++) {
      half[c][i] = hv[(i + c) % 4];
      uin[c][i] = (uint32_t)(i * 3 + c);
      flt[c][i] = (float)i * 0.125f + (float)c;
    }
  }
  const char *rgb[3] = {"R", "G", "B"};
  const char *ids[3] = {"id.B", "id.G", "id.R"}; /* deliberately not sorted */
  pc_err e;

  for (int storage = 0; storage < 2; storage++) {
    exr_storage_t st = storage ? EXR_STORAGE_TILED : EXR_STORAGE_SCANLINE;
    const char *ph = path_in(state, "half.exr");
    write_raw_exr(ph, w, h, st, EXR_PIXEL_HALF, rgb, 3, (void **)half);
    pc_image img;
    assert_int_equal(pc_image_read(ph, 1, &img, &e), PC_OK);
    for (int i = 0; i < w * h; i++)
      for (int c = 0; c < 3; c++) assert_true(img.rgb[3 * i + c] == hf[(i + c) % 4]);
    pc_image_free(&img);

    const char *pu = path_in(state, "uint.exr");
    void *idata[3] = {uin[2], uin[1], uin[0]};
    write_raw_exr(pu, w, h, st, EXR_PIXEL_UINT, ids, 3, idata);
    pc_exr_file f;
    assert_int_equal(pc_exr_read_layers(pu, &f, &e), PC_OK);
    assert_int_equal(f.nlayers, 1);
    assert_string_equal(f.names[0], "id");
    for (int i = 0; i < w * h; i++)
      for (int c = 0; c < 3; c++) assert_true(f.layers[0].rgb[3 * i + c] == (float)uin[c][i]);
    assert_string_equal(find_attr(&f, "someint"), "-42");
    assert_string_equal(find_attr(&f, "somefloat"), "0.25");
    pc_exr_file_free(&f);

    const char *pf = path_in(state, "float.exr");
    write_raw_exr(pf, w, h, st, EXR_PIXEL_FLOAT, rgb, 3, (void **)flt);
    assert_int_equal(pc_image_read(pf, 1, &img, &e), PC_OK);
    for (int i = 0; i < w * h; i++)
      for (int c = 0; c < 3; c++) assert_true(img.rgb[3 * i + c] == flt[c][i]);
    pc_image_free(&img);
  }
  for (int c = 0; c < 3; c++) {
    free(half[c]);
    free(uin[c]);
    free(flt[c]);
  }
}

static void test_exr_data_window(void **state) {
  const char *rgb[3] = {"R", "G", "B"};
  pc_err e;
  pc_image img;
  /* An origin away from (0,0) is honoured: pixel (0,0) of the result is dataWindow.min. */
  float *planes[3];
  for (int c = 0; c < 3; c++) {
    planes[c] = malloc(sizeof(float) * 6 * 4);
    for (int i = 0; i < 24; i++) planes[c][i] = (float)(100 * c + i);
  }
  for (int storage = 0; storage < 2; storage++) {
    const char *p = path_in(state, "dw.exr");
    write_raw_exr_at(p, -3, 5, 6, 4, storage ? EXR_STORAGE_TILED : EXR_STORAGE_SCANLINE,
                     EXR_PIXEL_FLOAT, rgb, 3, (void **)planes);
    assert_int_equal(pc_image_read(p, 1, &img, &e), PC_OK);
    assert_int_equal(img.w, 6);
    assert_int_equal(img.h, 4);
    for (int i = 0; i < 24; i++)
      for (int c = 0; c < 3; c++) assert_true(img.rgb[3 * i + c] == planes[c][i]);
    pc_image_free(&img);
  }
  for (int c = 0; c < 3; c++) free(planes[c]);

  /* Wider than PC_IMAGE_MAX_DIM: refused, never allocated. */
  const int w = PC_IMAGE_MAX_DIM + 100;
  float *zero = calloc((size_t)w, sizeof(float));
  void *zp[3] = {zero, zero, zero};
  const char *p = path_in(state, "wide.exr");
  write_raw_exr(p, w, 1, EXR_STORAGE_SCANLINE, EXR_PIXEL_FLOAT, rgb, 3, zp);
  expect_read_fails(p);
  pc_exr_file f;
  assert_true(pc_exr_read_layers(p, &f, &e) < 0);
  free(zero);
}

/* ---------------------------------------------------------------------------------------- */
/* PNG */

static float srgb_oetf(float v) {
  return v <= 0.0031308f ? 12.92f * v : 1.055f * powf(v, 1.0f / 2.4f) - 0.055f;
}

static void test_png_preview_roundtrip(void **state) {
  const int w = 37, h = 23;
  float *rgb = malloc(sizeof(float) * 3 * w * h);
  for (int i = 0; i < w * h * 3; i++) rgb[i] = (float)i / (float)(w * h * 3) * 0.7f - 0.05f;
  rgb[5] = NAN;
  rgb[6] = INFINITY;
  rgb[7] = -INFINITY;
  rgb[8] = 1e-4f;
  const char *path = path_in(state, "prev.png");
  pc_err e;
  const float exposure = 1.0f;
  assert_int_equal(pc_png_write_preview(path, w, h, rgb, exposure, &e), PC_OK);
  assert_true(no_temp_files(state));

  pc_image enc, lin;
  assert_int_equal(pc_image_read(path, 0, &enc, &e), PC_OK);
  assert_int_equal(pc_image_read(path, 1, &lin, &e), PC_OK);
  assert_int_equal(enc.w, w);
  assert_int_equal(enc.h, h);
  for (int i = 0; i < w * h * 3; i++) {
    float v = rgb[i] * 2.0f;
    if (!(v > 0.0f)) v = 0.0f;
    if (v > 1.0f) v = 1.0f;
    float want = srgb_oetf(v);
    assert_true(fabsf(enc.rgb[i] - want) <= 1.0f / 255.0f);
    assert_true(fabsf(srgb_oetf(lin.rgb[i]) - want) <= 1.0f / 255.0f + 1e-5f);
  }
  assert_true(enc.rgb[5] == 0.0f && enc.rgb[6] == 1.0f && enc.rgb[7] == 0.0f);
  pc_image_free(&enc);
  pc_image_free(&lin);

  assert_int_equal(pc_png_write_preview(path_in(state, "nodir/p.png"), w, h, rgb, 0, &e), PC_EIO);
  assert_int_equal(pc_png_write_preview(path, 0, h, rgb, 0, &e), PC_ELIMIT);
  free(rgb);
}

/* A PNG of any type written with libpng directly. */
static void write_png(const char *path, int w, int h, int depth, int ctype, int interlace,
                      const unsigned char *data, size_t rowbytes) {
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
  png_infop info = png_create_info_struct(png);
  if (setjmp(png_jmpbuf(png))) fail_msg("libpng failed writing %s", path);
  png_init_io(png, f);
  png_set_IHDR(png, info, w, h, depth, ctype, interlace, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  if (ctype == PNG_COLOR_TYPE_PALETTE) {
    png_color pal[3] = {{255, 0, 0}, {0, 255, 0}, {10, 20, 30}};
    png_set_PLTE(png, info, pal, 3);
  }
  png_write_info(png, info);
  png_bytep *rows = malloc(sizeof *rows * h);
  for (int y = 0; y < h; y++) rows[y] = (png_bytep)data + rowbytes * y;
  png_write_image(png, rows);
  png_write_end(png, NULL);
  png_destroy_write_struct(&png, &info);
  free(rows);
  fclose(f);
}

static void test_png_formats(void **state) {
  const int w = 5, h = 3;
  unsigned char buf[5 * 3 * 8];
  pc_image img;
  pc_err e;
  const char *p = path_in(state, "fmt.png");

  for (int i = 0; i < w * h; i++) buf[i] = (unsigned char)(i * 17);
  write_png(p, w, h, 8, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, buf, w);
  assert_int_equal(pc_image_read(p, 0, &img, &e), PC_OK);
  for (int i = 0; i < w * h; i++)
    for (int c = 0; c < 3; c++) assert_float_equal(img.rgb[3 * i + c], i * 17 / 255.0f, 1e-6);
  pc_image_free(&img);
  /* sRGB decode: 128 -> 0.2158605 */
  buf[0] = 128;
  write_png(p, w, h, 8, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, buf, w);
  assert_int_equal(pc_image_read(p, 1, &img, &e), PC_OK);
  assert_float_equal(img.rgb[0], 0.2158605f, 1e-5);
  pc_image_free(&img);

  for (int i = 0; i < w * h; i++) {
    buf[2 * i] = (unsigned char)(i * 10);
    buf[2 * i + 1] = 77; /* alpha, ignored */
  }
  write_png(p, w, h, 8, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_INTERLACE_NONE, buf, 2 * w);
  assert_int_equal(pc_image_read(p, 0, &img, &e), PC_OK);
  for (int i = 0; i < w * h; i++) assert_float_equal(img.rgb[3 * i + 2], i * 10 / 255.0f, 1e-6);
  pc_image_free(&img);

  for (int i = 0; i < w * h; i++) buf[i] = (unsigned char)(i % 3);
  write_png(p, w, h, 8, PNG_COLOR_TYPE_PALETTE, PNG_INTERLACE_NONE, buf, w);
  assert_int_equal(pc_image_read(p, 0, &img, &e), PC_OK);
  assert_float_equal(img.rgb[0], 1.0f, 1e-6);
  assert_float_equal(img.rgb[4], 1.0f, 1e-6);
  assert_float_equal(img.rgb[6], 10 / 255.0f, 1e-6);
  assert_float_equal(img.rgb[8], 30 / 255.0f, 1e-6);
  pc_image_free(&img);

  /* 16-bit RGB: big-endian samples */
  for (int i = 0; i < w * h * 3; i++) {
    unsigned v = (unsigned)i * 1000u + 7u;
    buf[2 * i] = (unsigned char)(v >> 8);
    buf[2 * i + 1] = (unsigned char)v;
  }
  write_png(p, w, h, 16, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, buf, 6 * w);
  assert_int_equal(pc_image_read(p, 0, &img, &e), PC_OK);
  for (int i = 0; i < w * h * 3; i++)
    assert_float_equal(img.rgb[i], (i * 1000 + 7) / 65535.0f, 1e-6);
  pc_image_free(&img);

  /* RGBA, interlaced */
  for (int i = 0; i < w * h * 4; i++) buf[i] = (unsigned char)(i * 3);
  write_png(p, w, h, 8, PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_ADAM7, buf, 4 * w);
  assert_int_equal(pc_image_read(p, 0, &img, &e), PC_OK);
  for (int i = 0; i < w * h; i++)
    for (int c = 0; c < 3; c++)
      assert_float_equal(img.rgb[3 * i + c], (4 * i + c) * 3 / 255.0f, 1e-6);
  pc_image_free(&img);

  /* 1-bit gray */
  memset(buf, 0xa0, sizeof buf); /* 1010 0000 */
  write_png(p, w, h, 1, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, buf, 1);
  assert_int_equal(pc_image_read(p, 0, &img, &e), PC_OK);
  assert_float_equal(img.rgb[0], 1.0f, 1e-6);
  assert_float_equal(img.rgb[3], 0.0f, 1e-6);
  assert_float_equal(img.rgb[6], 1.0f, 1e-6);
  pc_image_free(&img);
}

static void put_be32(unsigned char *p, uint32_t v) {
  p[0] = (unsigned char)(v >> 24);
  p[1] = (unsigned char)(v >> 16);
  p[2] = (unsigned char)(v >> 8);
  p[3] = (unsigned char)v;
}

static void test_png_huge_header_refused(void **state) {
  unsigned char b[8 + 25 + 12];
  static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a};
  memcpy(b, sig, 8);
  put_be32(b + 8, 13);
  memcpy(b + 12, "IHDR", 4);
  put_be32(b + 16, 100000);
  put_be32(b + 20, 100000);
  b[24] = 8; /* depth */
  b[25] = 2; /* RGB */
  b[26] = b[27] = b[28] = 0;
  put_be32(b + 29, (uint32_t)crc32(crc32(0, NULL, 0), b + 12, 17));
  put_be32(b + 33, 0); /* an empty IEND, never reached */
  memcpy(b + 37, "IEND", 4);
  put_be32(b + 41, (uint32_t)crc32(crc32(0, NULL, 0), b + 37, 4));
  const char *p = path_in(state, "huge.png");
  spit(p, b, sizeof b);
  pc_image img;
  pc_err e;
  assert_int_equal(pc_image_read(p, 1, &img, &e), PC_ELIMIT);
  assert_non_null(strstr(e.msg, "huge.png"));
}

/* A PNG cut inside its image data, whose header claims far more pixels than the rest can hold
 * (deflate expands at most 1032:1), is refused before its image is allocated; the whole file,
 * as compressible as PNG gets (zeros), reads. Interlaced and not. */
static void test_png_cut_data_refused(void **state) {
  const int w = 2048, h = 2048;
  unsigned char *zeros = calloc((size_t)w * h, 1);
  const char *p = path_in(state, "zeros.png"), *cut = path_in(state, "cut.png");
  for (int interlace = 0; interlace < 2; interlace++) {
    write_png(p, w, h, 8, PNG_COLOR_TYPE_GRAY, interlace ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE, zeros, w);
    pc_image img;
    pc_err e;
    assert_int_equal(pc_image_read(p, 1, &img, &e), PC_OK);
    assert_int_equal(img.w, w);
    assert_int_equal(img.h, h);
    assert_true(img.rgb[0] == 0.0f && img.rgb[3 * ((size_t)w * h - 1) + 2] == 0.0f);
    pc_image_free(&img);
    size_t n;
    unsigned char *b = slurp(p, &n);
    assert_true(n > 2000); /* 4 MiB of zeros: ~4 KB */
    spit(cut, b, 200);
    assert_int_equal(pc_image_read(cut, 1, &img, &e), PC_EIMAGE);
    assert_non_null(strstr(e.msg, "cut.png"));
    assert_non_null(strstr(e.msg, "2048x2048"));
    assert_non_null(strstr(e.msg, "image data can hold"));
    free(b);
  }
  free(zeros);
}

/* ---------------------------------------------------------------------------------------- */
/* JPEG */

static void write_jpeg(const char *path, int w, int h, int comps, const unsigned char *px, bool progressive) {
  struct jpeg_compress_struct ci;
  struct jpeg_error_mgr jerr;
  ci.err = jpeg_std_error(&jerr);
  jpeg_create_compress(&ci);
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  jpeg_stdio_dest(&ci, f);
  ci.image_width = (JDIMENSION)w;
  ci.image_height = (JDIMENSION)h;
  ci.input_components = comps;
  ci.in_color_space = comps == 3 ? JCS_RGB : JCS_GRAYSCALE;
  jpeg_set_defaults(&ci);
  jpeg_set_quality(&ci, 100, TRUE);
  if (progressive) jpeg_simple_progression(&ci);
  jpeg_start_compress(&ci, TRUE);
  while (ci.next_scanline < ci.image_height) {
    JSAMPROW row = (JSAMPROW)(px + (size_t)ci.next_scanline * w * comps);
    jpeg_write_scanlines(&ci, &row, 1);
  }
  jpeg_finish_compress(&ci);
  jpeg_destroy_compress(&ci);
  fclose(f);
}

static void test_jpeg_read(void **state) {
  const int w = 21, h = 13;
  unsigned char px[21 * 13 * 3];
  for (int i = 0; i < w * h; i++) {
    px[3 * i] = 200;
    px[3 * i + 1] = 100;
    px[3 * i + 2] = 50;
  }
  const char *p = path_in(state, "a.jpg");
  write_jpeg(p, w, h, 3, px, false);
  pc_image img;
  pc_err e;
  assert_int_equal(pc_image_read(p, 0, &img, &e), PC_OK);
  assert_int_equal(img.w, w);
  assert_int_equal(img.h, h);
  for (int i = 0; i < w * h; i++) {
    assert_float_equal(img.rgb[3 * i] * 255.0f, 200.0f, 3.0f);
    assert_float_equal(img.rgb[3 * i + 1] * 255.0f, 100.0f, 3.0f);
    assert_float_equal(img.rgb[3 * i + 2] * 255.0f, 50.0f, 3.0f);
  }
  pc_image_free(&img);

  memset(px, 128, sizeof px);
  write_jpeg(p, w, h, 1, px, false);
  assert_int_equal(pc_image_read(p, 1, &img, &e), PC_OK);
  for (int i = 0; i < w * h * 3; i++) assert_float_equal(img.rgb[i], 0.2158605f, 0.01f);
  pc_image_free(&img);
}

/* The image grows as its scanlines decode (a 512x1200 image takes four steps), progressive or
 * not; a header whose size is forged larger than the file can hold fails in one line: a
 * baseline file at its first missing data, a progressive one (whose coefficients libjpeg would
 * hold whole) before decoding. That neither takes the claimed image's memory first is what the
 * forged seeds of fuzz_files check, under libFuzzer's 1 GB limit. */
static void test_jpeg_sizes_not_trusted(void **state) {
  const int w = 512, h = 1200;
  unsigned char *px = malloc((size_t)w * h);
  for (int y = 0; y < h; y++) memset(px + (size_t)y * w, (y / 8) % 2 ? 200 : 40, (size_t)w);
  const char *p = path_in(state, "rows.jpg"), *forged = path_in(state, "forged.jpg");
  for (int progressive = 0; progressive < 2; progressive++) {
    write_jpeg(p, w, h, 1, px, progressive);
    pc_image img;
    pc_err e;
    assert_int_equal(pc_image_read(p, 0, &img, &e), PC_OK);
    assert_int_equal(img.w, w);
    assert_int_equal(img.h, h);
    for (int y = 0; y < h; y += 7)
      for (int x = 0; x < w; x += 13)
        assert_float_equal(img.rgb[3 * ((size_t)y * w + x) + 1] * 255.0f, ((y / 8) % 2 ? 200.0f : 40.0f), 3.0f);
    pc_image_free(&img);

    size_t n;
    unsigned char *b = slurp(p, &n);
    size_t sof = 0;
    for (size_t i = 2; i + 9 < n && !sof; i++)
      if (b[i] == 0xff && (b[i + 1] == 0xc0 || b[i + 1] == 0xc2)) sof = i;
    assert_true(sof > 0);
    b[sof + 5] = b[sof + 7] = 0x75; /* 30000 x 30000 */
    b[sof + 6] = b[sof + 8] = 0x30;
    spit(forged, b, n);
    assert_int_equal(pc_image_read(forged, 0, &img, &e), PC_EIMAGE);
    assert_non_null(strstr(e.msg, "forged.jpg"));
    if (progressive) assert_non_null(strstr(e.msg, "progressive 30000x30000"));
    free(b);
  }
  free(px);
}

/* pc_image_read_bytes keeps an 8-bit PNG (RGB, RGBA, grey, palette, interlaced) or a JPEG in its
 * bytes, every sample's value exactly the float pc_image_read gives, sRGB or not; a 16-bit PNG
 * stays in floats. */
static void test_image_read_bytes(void **state) {
  const int w = 7, h = 5;
  unsigned char px[7 * 5 * 4];
  for (size_t i = 0; i < sizeof px; i++) px[i] = (unsigned char)(i * 37 + 11);
  const char *p = path_in(state, "b.png"), *j = path_in(state, "b.jpg");
  struct { int ctype, interlace, per_px; } cases[] = {{PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, 3},
                                                       {PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_ADAM7, 4},
                                                       {PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, 1}};
  for (int k = 0; k < 5; k++) {
    if (k < 3) write_png(p, w, h, 8, cases[k].ctype, cases[k].interlace, px, (size_t)w * cases[k].per_px);
    else if (k == 3) write_jpeg(j, w, h, 3, px, false);
    else write_jpeg(j, w, h, 3, px, true);
    for (int srgb = 0; srgb < 2; srgb++) {
      pc_image f, b;
      pc_err e;
      assert_int_equal(pc_image_read(k < 3 ? p : j, srgb, &f, &e), PC_OK);
      assert_int_equal(pc_image_read_bytes(k < 3 ? p : j, srgb, &b, &e), PC_OK);
      assert_true(b.rgb == NULL && b.rgb8 != NULL && b.lut8 != NULL && f.rgb8 == NULL);
      assert_true(b.w == w && b.h == h);
      for (size_t i = 0; i < 3 * (size_t)w * h; i++) assert_true(pc_image_sample(&b, i) == f.rgb[i]);
      pc_image_free(&f);
      pc_image_free(&b);
    }
  }
  unsigned char px16[7 * 5 * 6] = {0};
  write_png(p, w, h, 16, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, px16, (size_t)w * 6);
  pc_image b;
  pc_err e;
  assert_int_equal(pc_image_read_bytes(p, 1, &b, &e), PC_OK);
  assert_true(b.rgb != NULL && b.rgb8 == NULL);
  pc_image_free(&b);
}

/* BMP and TGA (Mitsuba's bitmap reads both): 8-bit RGB, sRGB or not, the same samples through
 * pc_image_read and pc_image_read_bytes, as the PNG reader gives them; a TGA by its name, also
 * run-length coded; a header claiming more pixels than the file holds, or a file cut short, is
 * refused before decoding. */
/* Reads the 8-bit `file` as floats and as bytes, sRGB and not, and checks every sample against
 * the PNG `png` of the same w x h pixels. */
static void assert_reads_as_png(const char *file, const char *png, int w, int h) {
  for (int srgb = 0; srgb < 2; srgb++) {
    pc_image ref, f, b;
    pc_err e;
    assert_int_equal(pc_image_read(png, srgb, &ref, &e), PC_OK);
    int rc = pc_image_read(file, srgb, &f, &e);
    if (rc != PC_OK) print_error("%s\n", e.msg);
    assert_int_equal(rc, PC_OK);
    assert_int_equal(pc_image_read_bytes(file, srgb, &b, &e), PC_OK);
    assert_true(f.w == w && f.h == h && b.w == w && b.h == h && b.rgb8 && !b.rgb);
    for (size_t i = 0; i < 3 * (size_t)w * h; i++) assert_true(f.rgb[i] == ref.rgb[i] && pc_image_sample(&b, i) == ref.rgb[i]);
    pc_image_free(&ref);
    pc_image_free(&f);
    pc_image_free(&b);
  }
}

static void test_bmp_tga(void **state) {
  const int w = 9, h = 6;
  unsigned char px[9 * 6 * 3];
  for (size_t i = 0; i < sizeof px; i++) px[i] = (unsigned char)(i * 53 + 7);
  const char *png = path_in(state, "ref.png"), *bmp = path_in(state, "t.bmp"), *tga = path_in(state, "t.TGA"),
             *cut = path_in(state, "cut.bmp"), *forged = path_in(state, "forged.bmp");
  write_png(png, w, h, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, px, (size_t)w * 3);
  assert_true(stbi_write_bmp(bmp, w, h, 3, px));
  for (int rle = 0; rle < 2; rle++) {
    stbi_write_tga_with_rle = rle;
    assert_true(stbi_write_tga(tga, w, h, 3, px));
    assert_reads_as_png(bmp, png, w, h);
    assert_reads_as_png(tga, png, w, h);
  }
  size_t n;
  unsigned char *file = slurp(bmp, &n);
  spit(cut, file, n - 20);
  pc_image img;
  pc_err e;
  assert_int_equal(pc_image_read(cut, 1, &img, &e), PC_EPARSE);
  assert_non_null(strstr(e.msg, "truncated"));
  file[18] = 0x30, file[19] = 0x75, file[22] = 0x30, file[23] = 0x75; /* 30000 x 30000 */
  spit(forged, file, n);
  assert_int_equal(pc_image_read(forged, 1, &img, &e), PC_EPARSE);
  assert_non_null(strstr(e.msg, "cannot fit"));
  free(file);
  stbi_write_tga_with_rle = 0;
  assert_true(stbi_write_tga(tga, w, h, 3, px));
  file = slurp(tga, &n);
  spit(tga, file, n - 20);
  assert_int_equal(pc_image_read(tga, 1, &img, &e), PC_EPARSE);
  assert_non_null(strstr(e.msg, "truncated"));
  free(file);
}

/* PPM (P6) as Mitsuba reads it: 8-bit sRGB samples (the same as the PNG of those bytes); a
 * 16-bit one is refused, a short one is refused. */
static void test_ppm(void **state) {
  const int w = 5, h = 3;
  unsigned char px[5 * 3 * 3];
  for (size_t i = 0; i < sizeof px; i++) px[i] = (unsigned char)(i * 71 + 3);
  const char *png = path_in(state, "ref.png"), *ppm = path_in(state, "t.ppm");
  write_png(png, w, h, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, px, (size_t)w * 3);
  const char head[] = "P6\n# a comment\n5 3\n255\n";
  unsigned char file[sizeof head - 1 + sizeof px];
  memcpy(file, head, sizeof head - 1);
  memcpy(file + sizeof head - 1, px, sizeof px);
  spit(ppm, file, sizeof file);
  assert_reads_as_png(ppm, png, w, h);
  pc_image img;
  pc_err e;
  spit(ppm, file, sizeof file - 4);
  assert_int_equal(pc_image_read(ppm, 1, &img, &e), PC_EPARSE);
  assert_non_null(strstr(e.msg, "truncated"));
  assert_null(img.rgb);
  const char wide[] = "P6\n1 1\n65535\n\x12\x34\x56\x78\x9a\xbc";
  spit(ppm, (const unsigned char *)wide, sizeof wide - 1);
  assert_int_equal(pc_image_read(ppm, 1, &img, &e), PC_EUNSUPPORTED);
  assert_non_null(strstr(e.msg, "16-bit"));
}

/* Writes a PFM of the given header and 32-bit samples in the given byte order. */
static void write_pfm(const char *path, const char *head, const float *v, size_t n, bool little) {
  size_t hl = strlen(head);
  unsigned char *file = malloc(hl + 4 * n);
  memcpy(file, head, hl);
  for (size_t i = 0; i < n; i++) {
    uint32_t u;
    memcpy(&u, &v[i], 4);
    for (int k = 0; k < 4; k++) file[hl + 4 * i + k] = (unsigned char)(u >> (little ? 8 * k : 24 - 8 * k));
  }
  spit(path, file, hl + 4 * n);
  free(file);
}

/* PFM as Mitsuba reads it: linear floats, rows from the bottom, the scale's sign the byte order
 * and its magnitude a factor, grey replicated; malformed headers and short files refused. */
static void test_pfm(void **state) {
  const char *pfm = path_in(state, "t.pfm");
  /* 2 x 2 RGB, file rows bottom first */
  const float rgb[12] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
  for (int little = 0; little < 2; little++) {
    write_pfm(pfm, little ? "PF\n2 2\n-2.0\n" : "PF\n2 2\n2\n", rgb, 12, little);
    pc_image img;
    pc_err e;
    int rc = pc_image_read(pfm, 1, &img, &e);
    if (rc != PC_OK) print_error("%s\n", e.msg);
    assert_int_equal(rc, PC_OK);
    assert_true(img.w == 2 && img.h == 2 && img.rgb && !img.rgb8);
    /* the image's top row is the file's second */
    const float want[12] = {14, 16, 18, 20, 22, 24, 2, 4, 6, 8, 10, 12};
    for (int i = 0; i < 12; i++) assert_true(img.rgb[i] == want[i]);
    pc_image_free(&img);
  }
  const float grey[3] = {0.25f, 0.5f, 1e30f};
  write_pfm(pfm, "Pf 3 1 -1\n", grey, 3, true);
  pc_image img;
  pc_err e;
  assert_int_equal(pc_image_read_bytes(pfm, 1, &img, &e), PC_OK);
  assert_true(img.w == 3 && img.h == 1 && img.rgb);
  for (int i = 0; i < 9; i++) assert_true(img.rgb[i] == grey[i / 3]);
  pc_image_free(&img);
  const struct { const char *head; size_t n; const char *want; } bad[] = {
      {"PF\n2 2\n-1\n", 11, "truncated"},
      {"PF\n0 2\n-1\n", 0, "size"},
      {"PF\n2 40000\n-1\n", 0, "size"},
      {"PF\n2 2x\n-1\n", 12, "size"},
      {"PF\n2 2\n0\n", 12, "scale"},
      {"PF\n2 2\nnan\n", 12, "scale"},
      {"PF\n2 2", 0, "header"},
      {"PF\n2 2\n-1", 0, "header"},
      {"PF\n2 2\n-100000000000000000000000000000000000\n", 12, "header"},
      {"PFx2 2\n-1\n", 12, "not a PFM"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    write_pfm(pfm, bad[i].head, rgb, bad[i].n, true);
    memset(&img, 0, sizeof img);
    int rc = pc_image_read(pfm, 1, &img, &e);
    if (rc == PC_OK || !strstr(e.msg, bad[i].want)) print_error("case %zu: %s\n", i, rc ? e.msg : "read");
    assert_int_not_equal(rc, PC_OK);
    assert_non_null(strstr(e.msg, bad[i].want));
    assert_null(img.rgb);
  }
}

/* Radiance RGBE: flat scanlines (width < 8), value = mantissa * 2^(E - 136). */
static void test_rgbe_read(void **state) {
  const char head[] = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 3\n";
  const unsigned char px[2 * 3 * 4] = {128, 64, 32, 129, 128, 128, 128, 130, 0, 0, 0, 0,
                                       200, 100, 50, 136, 128, 0, 0, 128, 255, 255, 255, 120};
  unsigned char file[sizeof head - 1 + sizeof px];
  memcpy(file, head, sizeof head - 1);
  memcpy(file + sizeof head - 1, px, sizeof px);
  const char *p = path_in(state, "sky.hdr");
  spit(p, file, sizeof file);
  pc_image img;
  pc_err e;
  assert_int_equal(pc_image_read(p, 1, &img, &e), PC_OK); /* linear whatever the flag says */
  assert_int_equal(img.w, 3);
  assert_int_equal(img.h, 2);
  const float expect[] = {1.f, 0.5f, 0.25f, 2.f, 2.f, 2.f, 0.f, 0.f, 0.f, 200.f, 100.f, 50.f,
                          0.5f, 0.f, 0.f, 255.f / 65536.f, 255.f / 65536.f, 255.f / 65536.f};
  for (int i = 0; i < 18; i++) assert_float_equal(img.rgb[i], expect[i], 1e-6f * fmaxf(1.f, expect[i]));
  pc_image_free(&img);
  /* A header claiming more than PC_IMAGE_MAX_DIM pixels a side is refused before decoding. A
   * truncated body is read by stb_image as zeros (it has no end-of-data error): no crash. */
  spit(p, "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 40000\n", 49);
  expect_read_fails(p);
  spit(p, file, sizeof file - 10);
  if (pc_image_read(p, 1, &img, &e) == PC_OK) {
    assert_true(img.w == 3 && img.h == 2 && img.rgb[0] == 1.f);
    pc_image_free(&img);
  }
  /* stb_image would decode a header alone as zeros for every pixel it claims: one of 30000x30000
   * pixels in 53 bytes took minutes (found by fuzz_files). Refused at once for its size. */
  const char huge[] = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 30000 +X 30000\n";
  spit(p, huge, sizeof huge - 1);
  assert_int_equal(pc_image_read(p, 1, &img, &e), PC_EPARSE);
  assert_non_null(strstr(e.msg, "cannot fit"));
  /* The densest file stb decodes still reads: every scanline of 1016 pixels in 68 bytes, each
   * component 8 runs of 127 (4 rows: 4064 pixels in 272 bytes and the header). */
  enum { RW = 1016, RH = 4 };
  const char rhead[] = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 1016\n";
  unsigned char dense[sizeof rhead - 1 + RH * 68], *q = dense + sizeof rhead - 1;
  memcpy(dense, rhead, sizeof rhead - 1);
  for (int y = 0; y < RH; y++) {
    *q++ = 2, *q++ = 2, *q++ = RW >> 8, *q++ = RW & 0xff;
    for (int c = 0; c < 4; c++)
      for (int k = 0; k < 8; k++) *q++ = 128 + 127, *q++ = c == 3 ? 129 : 128; /* 0.5 * 2^(129-136) * 256 */
  }
  assert_int_equal((int)(q - dense), (int)sizeof dense);
  spit(p, dense, sizeof dense);
  assert_int_equal(pc_image_read(p, 1, &img, &e), PC_OK);
  assert_true(img.w == RW && img.h == RH);
  for (int i = 0; i < RW * RH * 3; i++) assert_float_equal(img.rgb[i], 1.f, 1e-6f);
  pc_image_free(&img);
  /* stb_image loops forever on a run-length count of 0, and past the end of a file it reads
   * zeros: fuzz_files' 67-byte file (8x2, cut in its first scanline) hung it. Both refused. */
  const char chead[] = "#?RGBE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 8\n";
  unsigned char cut[sizeof chead - 1 + 14], zero[sizeof chead - 1 + 2 * 12];
  static const unsigned char cut_px[14] = {2, 2, 0, 8, 0x88, 'd', 8, 'e', 0x88, 'f', 0x88, 'g', 2, 2};
  memcpy(cut, chead, sizeof chead - 1);
  memcpy(cut + sizeof chead - 1, cut_px, sizeof cut_px);
  spit(p, cut, sizeof cut);
  assert_int_equal(pc_image_read(p, 1, &img, &e), PC_EPARSE);
  assert_non_null(strstr(e.msg, "scanline 1"));
  memcpy(zero, chead, sizeof chead - 1);
  for (int y = 0; y < 2; y++) { /* complete scanlines of runs, the second's blue count 0 */
    unsigned char *z = zero + sizeof chead - 1 + 12 * y;
    static const unsigned char line[12] = {2, 2, 0, 8, 0x88, 128, 0x88, 128, 0x88, 128, 0x88, 129};
    memcpy(z, line, sizeof line);
    if (y == 1) z[8] = 0;
  }
  spit(p, zero, sizeof zero);
  assert_int_equal(pc_image_read(p, 1, &img, &e), PC_EPARSE);
  assert_non_null(strstr(e.msg, "scanline 2"));
  /* stb ends the header at a line that starts with a NUL as at an empty one: fuzz_files' file
   * of 2026-11-30 (8x2, cut in its first scanline after such a line) escaped the walk. */
  static const unsigned char nul_line[] = "#?RGBE\nFORMAT=32-bit_rle_rgbe\n\0\0\0\0\0\0\0F\n-Y 2 +X 8\n"
                                          "\2\2\0\10\210d\210e";
  spit(p, nul_line, sizeof nul_line - 1);
  assert_int_equal(pc_image_read(p, 1, &img, &e), PC_EPARSE);
  assert_non_null(strstr(e.msg, "scanline 1"));
  zero[sizeof chead - 1 + 12 + 8] = 0x88; /* mended: it reads */
  spit(p, zero, sizeof zero);
  assert_int_equal(pc_image_read(p, 1, &img, &e), PC_OK);
  assert_true(img.w == 8 && img.h == 2);
  pc_image_free(&img);
}

/* ---------------------------------------------------------------------------------------- */
/* Untrusted input */

static void test_missing_and_garbage(void **state) {
  pc_image img;
  pc_err e;
  assert_int_equal(pc_image_read(path_in(state, "nope.png"), 1, &img, &e), PC_EIO);
  assert_non_null(strstr(e.msg, "nope.png"));
  pc_exr_file f;
  assert_true(pc_exr_read_layers(path_in(state, "nope.exr"), &f, &e) < 0);
  spit(path_in(state, "empty"), "", 0);
  expect_read_fails(path_in(state, "empty"));
  unsigned char junk[4096];
  unsigned s = 12345;
  for (size_t i = 0; i < sizeof junk; i++) {
    s = s * 1103515245u + 12345u;
    junk[i] = (unsigned char)(s >> 16);
  }
  spit(path_in(state, "junk"), junk, sizeof junk);
  expect_read_fails(path_in(state, "junk"));
  /* right magic bytes, garbage after them */
  static const unsigned char magics[3][8] = {
      {0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a}, {0xff, 0xd8, 0xff}, {0x76, 0x2f, 0x31, 0x01}};
  for (int m = 0; m < 3; m++) {
    memcpy(junk, magics[m], 8);
    spit(path_in(state, "junkm"), junk, sizeof junk);
    expect_read_fails(path_in(state, "junkm"));
  }
}

/* Every prefix (stride `step`) of a good file must fail cleanly; random byte flips must not
 * crash (they may or may not be detected). */
static void truncate_and_corrupt(void **state, const char *good, size_t step) {
  size_t n;
  unsigned char *b = slurp(good, &n);
  const char *bad = path_in(state, "bad.img");
  for (size_t cut = 0; cut < n; cut += (cut < 64 ? 1 : step)) {
    spit(bad, b, cut);
    expect_read_fails(bad);
  }
  spit(bad, b, n - 1);
  expect_read_fails(bad);
  unsigned s = 777;
  unsigned char *c = malloc(n);
  for (int trial = 0; trial < 60; trial++) {
    memcpy(c, b, n);
    for (int k = 0; k < 4; k++) {
      s = s * 1103515245u + 12345u;
      size_t at = 8 + (s >> 8) % (n - 8); /* keep the magic so the codec is exercised */
      c[at] ^= (unsigned char)(1u << (s % 8));
    }
    spit(bad, c, n);
    pc_image img = {0};
    pc_err e;
    if (pc_image_read(bad, 1, &img, &e) == PC_OK) pc_image_free(&img);
    pc_exr_file f;
    if (pc_exr_read_layers(bad, &f, &e) == PC_OK) pc_exr_file_free(&f);
  }
  free(c);
  free(b);
}

static void test_truncated_and_corrupt_files(void **state) {
  const int w = 37, h = 23;
  float *rgb = pattern(w, h, 0.01f);
  pc_err e;
  const char *png = path_in(state, "t.png");
  assert_int_equal(pc_png_write_preview(png, w, h, rgb, 0, &e), PC_OK);
  truncate_and_corrupt(state, png, 3);

  const char *exr = path_in(state, "t.exr");
  pc_exr_layer layers[] = {{"", rgb}, {"pt", rgb}};
  pc_exr_attr at = {.name = "pcbpt.note", .type = PC_ATTR_STRING, .s = "x"};
  assert_int_equal(pc_exr_write(exr, w, h, layers, 2, &at, 1, &e), PC_OK);
  truncate_and_corrupt(state, exr, 29);

  unsigned char px[37 * 23 * 3];
  for (size_t i = 0; i < sizeof px; i++) px[i] = (unsigned char)(i * 7);
  const char *jpg = path_in(state, "t.jpg");
  write_jpeg(jpg, w, h, 3, px, false);
  truncate_and_corrupt(state, jpg, 3);
  free(rgb);
}

/* A header that claims a large data window over a file with no chunks for it fails when its
 * chunks are looked up, before the layers (here 30000x30000, 10.8 GB) are allocated. */
static void test_exr_huge_window_without_chunks(void **state) {
  float rgb[4 * 3 * 3] = {0};
  pc_exr_layer layer = {"", rgb};
  pc_err e;
  const char *p = path_in(state, "claims.exr");
  assert_int_equal(pc_exr_write(p, 4, 3, &layer, 1, NULL, 0, &e), PC_OK);
  size_t n;
  unsigned char *b = slurp(p, &n);
  static const char key[] = "dataWindow\0box2i\0";
  unsigned char *at = memmem(b, n, key, sizeof key - 1);
  assert_non_null(at);
  at += sizeof key - 1 + 4; /* the attribute's size, then xmin, ymin, xmax, ymax */
  const int32_t box[4] = {0, 0, 29999, 29999};
  memcpy(at, box, sizeof box); /* EXR is little-endian, as every machine we build on */
  spit(p, b, n);
  free(b);
  pc_exr_file f;
  assert_int_equal(pc_exr_read_layers(p, &f, &e), PC_EEXR);
  assert_non_null(strstr(e.msg, "claims.exr"));
  assert_non_null(strstr(e.msg, "chunks"));
}

/* ---------------------------------------------------------------------------------------- */
/* Metrics */

static void test_metrics_known_values(void **state) {
  (void)state;
  /* 2x1 image, reference b, test a = b + 0.5 */
  const float b[6] = {0, 1, 2, -1, 0.5f, 3};
  float a[6];
  for (int i = 0; i < 6; i++) a[i] = b[i] + 0.5f;
  pc_metrics m;
  pc_err e;
  assert_int_equal(pc_metrics_rgb(a, b, 2, 1, &m, &e), PC_OK);
  assert_float_equal(m.rmse, 0.5, 1e-12);
  assert_float_equal(m.l1, 0.5, 1e-12);
  double rel = 0;
  for (int i = 0; i < 6; i++) rel += 0.25 / ((double)b[i] * b[i] + 0.01);
  assert_float_equal(m.relmse, rel / 6, 1e-12);
  assert_float_equal(m.mean_b, 5.5 / 6, 1e-12);
  assert_float_equal(m.mean_a, 8.5 / 6, 1e-12);
  assert_int_equal(m.nonfinite, 0);

  /* mixed errors: RMSE != L1 */
  const float c[6] = {0, 1, 2, -1, 0.5f, 3 + 3};
  assert_int_equal(pc_metrics_rgb(c, b, 2, 1, &m, &e), PC_OK);
  assert_float_equal(m.rmse, sqrt(9.0 / 6), 1e-12);
  assert_float_equal(m.l1, 0.5, 1e-12);
  assert_float_equal(m.relmse, 9.0 / (9.01 * 6), 1e-12);

  float d[6];
  memcpy(d, a, sizeof d);
  d[2] = NAN;
  assert_int_equal(pc_metrics_rgb(d, b, 2, 1, &m, &e), PC_OK);
  assert_int_equal(m.nonfinite, 1);
  assert_float_equal(m.rmse, 0.5, 1e-12);

  pc_image ia = {.w = 2, .h = 1, .rgb = a}, ib = {.w = 1, .h = 2, .rgb = (float *)b};
  assert_int_equal(pc_metrics_image(&ia, &ib, &m, &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "2x1"));
}

static void test_metrics_layers(void **state) {
  (void)state;
  float z[3] = {0, 0, 0}, one[3] = {1, 1, 1}, two[3] = {2, 2, 2};
  char n0[] = "", n1[] = "pt", n2[] = "x", n3[] = "nee";
  char *an[] = {n0, n1, n2}, *bn[] = {n1, n3, n0};
  pc_image al[] = {{.w = 1, .h = 1, .rgb = one}, {.w = 1, .h = 1, .rgb = two}, {.w = 1, .h = 1, .rgb = z}};
  pc_image bl[] = {{.w = 1, .h = 1, .rgb = z}, {.w = 1, .h = 1, .rgb = z}, {.w = 1, .h = 1, .rgb = z}};
  pc_exr_file a = {.w = 1, .h = 1, .nlayers = 3, .names = an, .layers = al};
  pc_exr_file b = {.w = 1, .h = 1, .nlayers = 3, .names = bn, .layers = bl};
  pc_layer_metrics *r;
  int n;
  pc_err e;
  assert_int_equal(pc_metrics_layers(&a, &b, &r, &n, &e), PC_OK);
  assert_int_equal(n, 2);
  assert_string_equal(r[0].name, "");
  assert_float_equal(r[0].m.rmse, 1.0, 1e-12);
  assert_string_equal(r[1].name, "pt");
  assert_float_equal(r[1].m.l1, 2.0, 1e-12);
  assert_float_equal(r[1].m.relmse, 4.0 / 0.01, 1e-9);
  pc_layer_metrics_free(r, n);

  b.nlayers = 2;
  bn[0] = n3;
  bn[1] = n3;
  assert_int_equal(pc_metrics_layers(&a, &b, &r, &n, &e), PC_EINVAL);
  b.w = 2;
  assert_int_equal(pc_metrics_layers(&a, &b, &r, &n, &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "differ"));
}

/* A Git LFS pointer where an image should be (a repository cloned without Git LFS): named as
 * such, whatever the file's extension. */
static void test_lfs_pointer(void **state) {
  const char *ptr = "version https://git-lfs.github.com/spec/v1\noid sha256:534331e9438284caf604721d76be1a2313277cb4e645cb0123456789abcdef01\nsize 1048576\n";
  const char *names[] = {"t.png", "t.jpg", "t.exr", "t.tga", "t.pfm"};
  for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
    const char *p = path_in(state, names[i]);
    spit(p, ptr, strlen(ptr));
    pc_image img;
    pc_err e = {0};
    assert_int_equal(pc_image_read(p, true, &img, &e), PC_EINVAL);
    if (!strstr(e.msg, "a Git LFS pointer, not the file itself")) print_error("%s: %s\n", names[i], e.msg);
    assert_non_null(strstr(e.msg, "a Git LFS pointer, not the file itself"));
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_exr_roundtrip, setup, teardown),
      cmocka_unit_test_setup_teardown(test_bmp_tga, setup, teardown),
      cmocka_unit_test_setup_teardown(test_ppm, setup, teardown),
      cmocka_unit_test_setup_teardown(test_lfs_pointer, setup, teardown),
      cmocka_unit_test_setup_teardown(test_pfm, setup, teardown),
      cmocka_unit_test_setup_teardown(test_exr_no_beauty_gives_first_triplet, setup, teardown),
      cmocka_unit_test_setup_teardown(test_exr_write_errors, setup, teardown),
      cmocka_unit_test_setup_teardown(test_exr_write_rows, setup, teardown),
      cmocka_unit_test_setup_teardown(test_exr_half_uint_tiled, setup, teardown),
      cmocka_unit_test_setup_teardown(test_exr_data_window, setup, teardown),
      cmocka_unit_test_setup_teardown(test_png_preview_roundtrip, setup, teardown),
      cmocka_unit_test_setup_teardown(test_png_formats, setup, teardown),
      cmocka_unit_test_setup_teardown(test_png_cut_data_refused, setup, teardown),
      cmocka_unit_test_setup_teardown(test_png_huge_header_refused, setup, teardown),
      cmocka_unit_test_setup_teardown(test_jpeg_read, setup, teardown),
      cmocka_unit_test_setup_teardown(test_jpeg_sizes_not_trusted, setup, teardown),
      cmocka_unit_test_setup_teardown(test_image_read_bytes, setup, teardown),
      cmocka_unit_test_setup_teardown(test_rgbe_read, setup, teardown),
      cmocka_unit_test_setup_teardown(test_missing_and_garbage, setup, teardown),
      cmocka_unit_test_setup_teardown(test_truncated_and_corrupt_files, setup, teardown),
      cmocka_unit_test_setup_teardown(test_exr_huge_window_without_chunks, setup, teardown),
      cmocka_unit_test(test_metrics_known_values),
      cmocka_unit_test(test_metrics_layers),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
