/* bundle.c: collecting, hashing and safely unpacking scene bundles. */
#include "bundle.h"

#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <libgen.h>
#include <sodium.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zstd.h>

#include "pcbpt.pb-c.h"
#include "big_alloc.h"
#include "file_read.h"
#include "wire_film.h"

static int read_file(const char *path, uint8_t **out, size_t *n, pc_err *e) {
  int fd = open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return pc_errf(e, PC_EIO, "%s: %s", path, strerror(errno));
  struct stat st;
  if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    close(fd);
    return pc_errf(e, PC_EIO, "%s: not a readable regular file", path);
  }
  if ((size_t)st.st_size > PC_BUNDLE_MAX) {
    close(fd);
    return pc_errf(e, PC_ELIMIT, "%s: %lld bytes exceeds the bundle limit", path, (long long)st.st_size);
  }
  uint8_t *b = pc_big_alloc((size_t)st.st_size + 1);
  if (!b) { close(fd); return pc_errf(e, PC_ENOMEM, "%s: out of memory", path); }
  size_t got = 0;
  while (got < (size_t)st.st_size) {
    ssize_t r = read(fd, b + got, (size_t)st.st_size - got);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) {
      int err = r < 0 ? errno : EIO;
      free(b);
      close(fd);
      return pc_errf(e, PC_EIO, "%s: read: %s", path, strerror(err));
    }
    got += (size_t)r;
  }
  close(fd);
  *out = b;
  *n = got;
  return 0;
}

int pc_bundle_path_ok(const char *rel) {
  size_t len = strlen(rel);
  if (len == 0 || len >= PC_BUNDLE_MAX_PATH || rel[0] == '/') return 0;
  for (const char *c = rel; *c; c++)
    if (*c == '\\' || (unsigned char)*c < 0x20 || *c == 0x7f) return 0;
  const char *s = rel;
  for (;;) {
    const char *slash = strchr(s, '/');
    size_t cl = slash ? (size_t)(slash - s) : strlen(s);
    if (cl == 0 || (cl == 1 && s[0] == '.') || (cl == 2 && s[0] == '.' && s[1] == '.')) return 0;
    if (!slash) return 1;
    s = slash + 1;
  }
}

int pc_bundle_hash(const uint8_t *blob, size_t n, uint8_t hash[PC_BUNDLE_HASH], pc_err *e) {
  if (crypto_generichash(hash, PC_BUNDLE_HASH, blob, n, NULL, 0) != 0) return pc_errf(e, PC_EIO, "bundle: hashing failed");
  return 0;
}

void pc_bundle_hex(const uint8_t hash[PC_BUNDLE_HASH], char out[2 * PC_BUNDLE_HASH + 1]) {
  sodium_bin2hex(out, 2 * PC_BUNDLE_HASH + 1, hash, PC_BUNDLE_HASH);
}

int pc_bundle_unhex(const char *hex, uint8_t hash[PC_BUNDLE_HASH]) {
  size_t bin_len = 0;
  if (strlen(hex) != 2 * PC_BUNDLE_HASH ||
      sodium_hex2bin(hash, PC_BUNDLE_HASH, hex, strlen(hex), NULL, &bin_len, NULL) != 0 || bin_len != PC_BUNDLE_HASH)
    return PC_EINVAL;
  return 0;
}

int pc_bundle_create(const char *const *files, const char *const *names, int nfiles, uint8_t **blob, size_t *n,
                     uint8_t hash[PC_BUNDLE_HASH], pc_err *e) {
  if (nfiles < 1) return pc_errf(e, PC_EINVAL, "bundle: no scene file");
  if (nfiles > PC_BUNDLE_MAX_FILES) return pc_errf(e, PC_ELIMIT, "bundle: more than %d files", PC_BUNDLE_MAX_FILES);
  Pcbpt__BundleFile *bf = calloc((size_t)nfiles, sizeof *bf);
  Pcbpt__BundleFile **fp = calloc((size_t)nfiles, sizeof *fp);
  int rc = bf && fp ? 0 : pc_errf(e, PC_ENOMEM, "bundle: out of memory");
  int done = 0;
  size_t total = 0;
  for (; !rc && done < nfiles; done++) {
    const char *rel = names[done];
    if (!pc_bundle_path_ok(rel)) {
      rc = pc_errf(e, PC_EINVAL, "bundle: '%.200s' is not a relative path inside the scene's folder", rel);
      break;
    }
    uint8_t *d = NULL;
    size_t dn = 0;
    if ((rc = read_file(files[done], &d, &dn, e)) != 0) break;
    pcbpt__bundle_file__init(&bf[done]);
    bf[done].path = (char *)rel;
    bf[done].data.data = d;
    bf[done].data.len = dn;
    fp[done] = &bf[done];
    total += dn;
    if (total > PC_BUNDLE_MAX) rc = pc_errf(e, PC_ELIMIT, "%s: scene and its files exceed %zu bytes", files[0], PC_BUNDLE_MAX);
  }
  if (!rc) {
    Pcbpt__Bundle b = PCBPT__BUNDLE__INIT;
    b.scene = bf[0].path;
    b.n_files = (size_t)nfiles;
    b.files = fp;
    size_t len = pcbpt__bundle__get_packed_size(&b);
    uint8_t *raw = pc_big_alloc(len);
    if (!raw) rc = pc_errf(e, PC_ENOMEM, "bundle: out of memory for %zu bytes", len);
    else {
      pcbpt__bundle__pack(&b, raw);
      rc = pc_wire_compress(raw, len, blob, n, e);
      free(raw);
      if (!rc && (rc = pc_bundle_hash(*blob, *n, hash, e)) != 0) free(*blob);
    }
  }
  for (int i = 0; i < done && bf; i++) free(bf[i].data.data);
  free(bf);
  free(fp);
  return rc;
}

static int rm_entry(const char *p, const struct stat *sb, int flag, struct FTW *f) {
  (void)sb; (void)flag; (void)f;
  return remove(p);
}

/* Creates every parent directory of rel under root; rel is already checked safe. */
static int make_parents(const char *root, const char *rel, pc_err *e) {
  char p[PATH_MAX];
  if ((size_t)snprintf(p, sizeof p, "%s/%s", root, rel) >= sizeof p) return pc_errf(e, PC_ELIMIT, "bundle: path too long");
  size_t skip = strlen(root) + 1;
  for (char *c = p + skip; *c; c++) {
    if (*c != '/') continue;
    *c = 0;
    if (mkdir(p, 0700) != 0 && errno != EEXIST) return pc_errf(e, PC_EIO, "bundle: mkdir %s: %s", p, strerror(errno));
    *c = '/';
  }
  return 0;
}

int pc_bundle_dir(const char *cache_dir, const uint8_t hash[PC_BUNDLE_HASH], char *out, size_t out_size) {
  char hex[2 * PC_BUNDLE_HASH + 1];
  pc_bundle_hex(hash, hex);
  return (size_t)snprintf(out, out_size, "%s/%s", cache_dir, hex) < out_size ? 0 : PC_ELIMIT;
}

int pc_bundle_lookup(const char *cache_dir, const uint8_t hash[PC_BUNDLE_HASH], char *scene_out, size_t scene_out_size) {
  char hex[2 * PC_BUNDLE_HASH + 1], marker[PATH_MAX];
  pc_bundle_hex(hash, hex);
  if ((size_t)snprintf(marker, sizeof marker, "%s/%s.scene", cache_dir, hex) >= sizeof marker) return 0;
  FILE *f = fopen(marker, "r");
  if (!f) return 0;
  char rel[PC_BUNDLE_MAX_PATH + 2] = {0};
  int ok = fgets(rel, sizeof rel, f) != NULL;
  fclose(f);
  if (!ok || !pc_bundle_path_ok(rel)) return 0;
  return (size_t)snprintf(scene_out, scene_out_size, "%s/%s/%s", cache_dir, hex, rel) < scene_out_size;
}

/* protobuf-c copies each file's bytes out of the message: in huge pages when large. */
static void *big_pb_alloc(void *data, size_t n) { (void)data; return pc_big_alloc(n); }
static void big_pb_free(void *data, void *p) { (void)data; free(p); }

int pc_bundle_unpack(const uint8_t *blob, size_t n, const uint8_t hash[PC_BUNDLE_HASH], const char *cache_dir,
                     char *scene_out, size_t scene_out_size, pc_err *e) {
  uint8_t got[PC_BUNDLE_HASH];
  char hex[2 * PC_BUNDLE_HASH + 1];
  int rc = pc_bundle_hash(blob, n, got, e);
  if (rc) return rc;
  pc_bundle_hex(hash, hex);
  if (sodium_memcmp(got, hash, PC_BUNDLE_HASH) != 0)
    return pc_errf(e, PC_EINVAL, "bundle %.16s...: content hash does not match its address", hex);
  if (pc_bundle_lookup(cache_dir, hash, scene_out, scene_out_size)) return 0;
  /* Bounded by PC_BUNDLE_MAX before allocating: the header is untrusted. */
  unsigned long long cs = ZSTD_getFrameContentSize(blob, n);
  if (cs > PC_BUNDLE_MAX) return pc_errf(e, PC_ELIMIT, "bundle %.16s...: bad or oversized content size", hex);
  uint8_t *raw = NULL;
  if ((rc = pc_wire_decompress(blob, n, (size_t)cs, PC_BUNDLE_MAX, &raw, e)) != 0) return rc;
  ProtobufCAllocator big_pb = {big_pb_alloc, big_pb_free, NULL};
  Pcbpt__Bundle *b = pcbpt__bundle__unpack(&big_pb, (size_t)cs, raw);
  free(raw);
  if (!b) return pc_errf(e, PC_EPARSE, "bundle %.16s...: malformed contents", hex);
  int has_scene = 0;
  if (!pc_bundle_path_ok(b->scene) || b->n_files > PC_BUNDLE_MAX_FILES) rc = pc_errf(e, PC_EINVAL, "bundle %.16s...: bad scene path or too many files", hex);
  for (size_t i = 0; !rc && i < b->n_files; i++) {
    if (!pc_bundle_path_ok(b->files[i]->path)) rc = pc_errf(e, PC_EINVAL, "bundle %.16s...: unsafe path '%.64s'", hex, b->files[i]->path);
    if (strcmp(b->files[i]->path, b->scene) == 0) has_scene = 1;
  }
  if (!rc && !has_scene) rc = pc_errf(e, PC_EINVAL, "bundle %.16s...: scene file '%.64s' missing", hex, b->scene);
  char tmp[PATH_MAX], final[PATH_MAX], marker[PATH_MAX], mtmp[PATH_MAX];
  if (!rc && ((size_t)snprintf(tmp, sizeof tmp, "%s/%s.tmp.%ld.%08x", cache_dir, hex, (long)getpid(), randombytes_random()) >= sizeof tmp ||
              (size_t)snprintf(final, sizeof final, "%s/%s", cache_dir, hex) >= sizeof final ||
              (size_t)snprintf(marker, sizeof marker, "%s/%s.scene", cache_dir, hex) >= sizeof marker ||
              (size_t)snprintf(mtmp, sizeof mtmp, "%s.%08x", tmp, randombytes_random()) >= sizeof mtmp))
    rc = pc_errf(e, PC_ELIMIT, "bundle: cache path too long");
  if (!rc && mkdir(cache_dir, 0700) != 0 && errno != EEXIST) rc = pc_errf(e, PC_EIO, "bundle: mkdir %s: %s", cache_dir, strerror(errno));
  if (!rc && mkdir(tmp, 0700) != 0) rc = pc_errf(e, PC_EIO, "bundle: mkdir %s: %s", tmp, strerror(errno));
  int made_tmp = !rc;
  for (size_t i = 0; !rc && i < b->n_files; i++) {
    if ((rc = make_parents(tmp, b->files[i]->path, e)) != 0) break;
    char p[PATH_MAX];
    int pn = snprintf(p, sizeof p, "%s/%s", tmp, b->files[i]->path);
    if (pn < 0 || (size_t)pn >= sizeof p) { rc = pc_errf(e, PC_ELIMIT, "bundle: cache path too long for %s", b->files[i]->path); break; }
    int fd = open(p, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
    if (fd < 0) { rc = pc_errf(e, PC_EIO, "bundle: create %s: %s", p, strerror(errno)); break; }
    if (pc_write_all(fd, b->files[i]->data.data, b->files[i]->data.len) != 0 || close(fd) != 0)
      rc = pc_errf(e, PC_EIO, "bundle: write %s: %s", p, strerror(errno));
  }
  if (!rc && rename(tmp, final) != 0) {
    if (errno == EEXIST || errno == ENOTEMPTY) nftw(tmp, rm_entry, 16, FTW_DEPTH | FTW_PHYS);
    else rc = pc_errf(e, PC_EIO, "bundle: rename to %s: %s", final, strerror(errno));
  } else if (rc && made_tmp) {
    nftw(tmp, rm_entry, 16, FTW_DEPTH | FTW_PHYS);
  }
  if (!rc) {
    FILE *f = fopen(mtmp, "w");
    int bad = !f;
    if (f) {
      bad = fputs(b->scene, f) < 0;
      bad |= fclose(f) != 0;
    }
    if (bad || rename(mtmp, marker) != 0) rc = pc_errf(e, PC_EIO, "bundle: writing %s: %s", marker, strerror(errno));
  }
  if (!rc && (size_t)snprintf(scene_out, scene_out_size, "%s/%s", final, b->scene) >= scene_out_size)
    rc = pc_errf(e, PC_ELIMIT, "bundle: scene path too long");
  pcbpt__bundle__free_unpacked(b, &big_pb);
  return rc;
}
