/* bundle.c: collecting, hashing and safely unpacking scene bundles. */
#include "bundle.h"

#include <errno.h>
#include <expat.h>
#include <fcntl.h>
#include <ftw.h>
#include <libgen.h>
#include <sodium.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zstd.h>

#include "pcbpt.pb-c.h"
#include "file_read.h"
#include "wire_film.h"

typedef struct refs {
  char **paths;
  int n;
  int error;       /* first problem found while parsing, reported after */
  char bad[512];
  XML_Parser parser;
} refs;

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
  uint8_t *b = malloc((size_t)st.st_size + 1);
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

static void XMLCALL on_start(void *ud, const XML_Char *el, const XML_Char **attr) {
  refs *r = ud;
  if (r->error || strcmp(el, "string") != 0) return;
  const char *name = NULL, *value = NULL;
  for (int i = 0; attr[i]; i += 2) {
    if (strcmp(attr[i], "name") == 0) name = attr[i + 1];
    else if (strcmp(attr[i], "value") == 0) value = attr[i + 1];
  }
  if (!name || !value || strcmp(name, "filename") != 0) return;
  /* "./m.obj" and "sub//m.obj" name files the loader finds: bundled as "m.obj", "sub/m.obj" */
  char norm[PC_BUNDLE_MAX_PATH + 1];
  size_t k = 0;
  for (const char *s = value; *s && k < sizeof norm - 1;) {
    const char *slash = strchr(s, '/');
    size_t cl = slash ? (size_t)(slash - s) : strlen(s);
    bool skip = cl == 0 || (cl == 1 && s[0] == '.');
    if (!skip && k + cl + 1 < sizeof norm) {
      if (k) norm[k++] = '/';
      memcpy(norm + k, s, cl);
      k += cl;
    } else if (!skip) {
      k = sizeof norm - 1;
    }
    s += cl + (slash ? 1 : 0);
  }
  norm[k] = 0;
  if (value[0] == '/' || !pc_bundle_path_ok(norm)) {
    r->error = PC_EINVAL;
    snprintf(r->bad, sizeof r->bad, "line %lu: referenced file '%.200s' %s", (unsigned long)XML_GetCurrentLineNumber(r->parser),
             value, value[0] == '/' ? "is an absolute path (paths are relative to the scene's folder)"
                    : strlen(value) >= PC_BUNDLE_MAX_PATH ? "is a path too long"
                    : "is not a path inside the scene's folder");
    return;
  }
  value = norm;
  for (int i = 0; i < r->n; i++)
    if (strcmp(r->paths[i], value) == 0) return;
  if (r->n >= PC_BUNDLE_MAX_FILES) {
    r->error = PC_ELIMIT;
    snprintf(r->bad, sizeof r->bad, "more than %d referenced files", PC_BUNDLE_MAX_FILES);
    return;
  }
  char **np = realloc(r->paths, sizeof *np * (size_t)(r->n + 1));
  char *dup = strdup(value);
  if (!np || !dup) {
    if (np) r->paths = np;
    free(dup);
    r->error = PC_ENOMEM;
    snprintf(r->bad, sizeof r->bad, "out of memory");
    return;
  }
  r->paths = np;
  r->paths[r->n++] = dup;
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

/* The real path of the file dir/rel, which must lie inside dir (itself a real path): a
 * symlink may point anywhere within the scene's folder, never out of it. */
static int resolve_inside(const char *scene_path, const char *dir, const char *rel, char out[PATH_MAX], pc_err *e) {
  char full[PATH_MAX];
  if ((size_t)snprintf(full, sizeof full, "%s/%s", dir, rel) >= sizeof full)
    return pc_errf(e, PC_ELIMIT, "%s: path of '%s' too long", scene_path, rel);
  if (!realpath(full, out)) return pc_errf(e, PC_EIO, "%s: referenced file '%s': %s", scene_path, rel, strerror(errno));
  size_t dn = strlen(dir);
  if (strncmp(out, dir, dn) != 0 || (out[dn] != '/' && dn != 1))
    return pc_errf(e, PC_EINVAL, "%s: referenced file '%s' is a link out of the scene's folder %s", scene_path, rel, dir);
  return 0;
}

int pc_bundle_create(const char *scene_arg, uint8_t **blob, size_t *n, uint8_t hash[PC_BUNDLE_HASH], pc_err *e) {
  /* resolved once: the scene's folder is where the scene file really is, as for the loader */
  char scene_path[PATH_MAX];
  if (!realpath(scene_arg, scene_path)) return pc_errf(e, PC_EIO, "%s: %s", scene_arg, strerror(errno));
  uint8_t *xml = NULL;
  size_t xml_n = 0;
  int rc = read_file(scene_path, &xml, &xml_n, e);
  if (rc) return rc;
  refs r = {0};
  r.parser = XML_ParserCreate(NULL);
  if (!r.parser) { free(xml); return pc_errf(e, PC_ENOMEM, "%s: cannot create an XML parser", scene_path); }
  XML_SetUserData(r.parser, &r);
  XML_SetStartElementHandler(r.parser, on_start);
  if (xml_n > (size_t)INT32_MAX || XML_Parse(r.parser, (const char *)xml, (int)xml_n, 1) == XML_STATUS_ERROR) {
    rc = pc_errf(e, PC_EPARSE, "%s:%lu: %s", scene_path, (unsigned long)XML_GetCurrentLineNumber(r.parser),
                 XML_ErrorString(XML_GetErrorCode(r.parser)));
  } else if (r.error) {
    rc = pc_errf(e, r.error, "%s: %s", scene_path, r.bad);
  }
  XML_ParserFree(r.parser);

  char *pathcopy = strdup(scene_path), *pathcopy2 = strdup(scene_path);
  Pcbpt__BundleFile *files = calloc((size_t)r.n + 1, sizeof *files);
  Pcbpt__BundleFile **fp = calloc((size_t)r.n + 1, sizeof *fp);
  if (!rc && (!pathcopy || !pathcopy2 || !files || !fp)) rc = pc_errf(e, PC_ENOMEM, "bundle: out of memory");
  int nfiles = 0;
  size_t total = xml_n;
  if (!rc) {
    const char *dir = dirname(pathcopy), *base = basename(pathcopy2);
    pcbpt__bundle_file__init(&files[0]);
    files[0].path = (char *)base;
    files[0].data.data = xml;
    files[0].data.len = xml_n;
    fp[0] = &files[0];
    nfiles = 1;
    /* the sizes first: a scene too large to bundle is refused before anything is read */
    unsigned long long sum = xml_n;
    for (int i = 0; i < r.n && !rc; i++) {
      char full[PATH_MAX];
      struct stat st;
      if (strcmp(r.paths[i], base) == 0) continue;
      if ((rc = resolve_inside(scene_arg, dir, r.paths[i], full, e)) != 0) break;
      if (stat(full, &st) == 0 && st.st_size > 0) sum += (unsigned long long)st.st_size;
      if (sum > PC_BUNDLE_MAX)
        rc = pc_errf(e, PC_ELIMIT, "%s: scene and its files exceed %zu bytes (at '%s')", scene_arg, PC_BUNDLE_MAX, r.paths[i]);
    }
    for (int i = 0; i < r.n && !rc; i++) {
      if (strcmp(r.paths[i], base) == 0) continue;
      char full[PATH_MAX];
      if ((rc = resolve_inside(scene_arg, dir, r.paths[i], full, e)) != 0) break;
      uint8_t *d;
      size_t dn;
      if ((rc = read_file(full, &d, &dn, e)) != 0) break;
      total += dn;
      pcbpt__bundle_file__init(&files[nfiles]);
      files[nfiles].path = r.paths[i];
      files[nfiles].data.data = d;
      files[nfiles].data.len = dn;
      fp[nfiles] = &files[nfiles];
      nfiles++;
      if (total > PC_BUNDLE_MAX) rc = pc_errf(e, PC_ELIMIT, "%s: scene and its files exceed %zu bytes", scene_path, PC_BUNDLE_MAX);
    }
  }
  if (!rc) {
    Pcbpt__Bundle b = PCBPT__BUNDLE__INIT;
    b.scene = files[0].path;
    b.n_files = (size_t)nfiles;
    b.files = fp;
    size_t len = pcbpt__bundle__get_packed_size(&b);
    uint8_t *raw = malloc(len ? len : 1);
    if (!raw) rc = pc_errf(e, PC_ENOMEM, "bundle: out of memory for %zu bytes", len);
    else {
      pcbpt__bundle__pack(&b, raw);
      rc = pc_wire_compress(raw, len, blob, n, e);
      free(raw);
      if (!rc && (rc = pc_bundle_hash(*blob, *n, hash, e)) != 0) free(*blob);
    }
  }
  for (int i = 1; i < nfiles; i++) free(files[i].data.data);
  free(files);
  free(fp);
  free(pathcopy);
  free(pathcopy2);
  free(xml);
  for (int i = 0; i < r.n; i++) free(r.paths[i]);
  free(r.paths);
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
  Pcbpt__Bundle *b = pcbpt__bundle__unpack(NULL, (size_t)cs, raw);
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
  pcbpt__bundle__free_unpacked(b, NULL);
  return rc;
}
