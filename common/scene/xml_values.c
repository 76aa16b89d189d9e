/* xml_values.c: parsing of Mitsuba 0.6 value elements (numbers, colours, transforms, IOR
 * names); see xml_values.h. */
#include "xml_values.h"

#include "spectrum.h"

#include <ctype.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

int pc_xv_numbers(const char *file, const pc_xml_node *n, const char *attr, const char *s, double *out,
                  int min, int max, int *count, pc_err *e) {
  int k = 0;
  if (!s) return pc_errf(e, PC_EPARSE, "%s:%d: <%s> lacks attribute '%s'", file, n->line, n->name, attr);
  const char *p = s;
  for (;;) {
    while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r' || *p == ',') p++;
    if (!*p) break;
    if (k == max)
      return pc_errf(e, PC_EPARSE, "%s:%d: <%s> attribute '%s' has more than %d numbers", file, n->line, n->name, attr, max);
    char *end;
    double d = strtod(p, &end);
    if (end == p || !(*end == 0 || *end == ' ' || *end == ',' || *end == '\t' || *end == '\n' || *end == '\r'))
      return pc_errf(e, PC_EPARSE, "%s:%d: <%s> attribute '%s' is not a number list: '%.40s'", file, n->line, n->name, attr, s);
    if (!isfinite(d))
      return pc_errf(e, PC_ENUMERIC, "%s:%d: <%s> attribute '%s' has a non-finite number", file, n->line, n->name, attr);
    out[k++] = d;
    p = end;
  }
  if (k < min)
    return pc_errf(e, PC_EPARSE, "%s:%d: <%s> attribute '%s' needs %d number%s", file, n->line, n->name, attr, min,
                   min > 1 ? "s" : "");
  *count = k;
  return 0;
}

int pc_xv_number(const char *file, const pc_xml_node *n, const char *attr, double *out, pc_err *e) {
  int k;
  return pc_xv_numbers(file, n, attr, pc_xml_attr(n, attr), out, 1, 1, &k, e);
}

/* "400:0.5, 500:0.6, ..." */
static int sampled_spectrum(const char *file, const pc_xml_node *n, const char *val, double rgb[3], pc_err *e) {
  double *l = malloc(2 * PC_SPECTRUM_MAX_SAMPLES * sizeof *l);
  if (!l) return pc_errf(e, PC_ENOMEM, "%s:%d: out of memory", file, n->line);
  double *v = l + PC_SPECTRUM_MAX_SAMPLES;
  int m = 0, rc = 0;
  const char *p = val;
  for (;;) {
    while (*p == ' ' || *p == ',' || *p == '\t' || *p == '\n' || *p == '\r') p++;
    if (!*p) break;
    if (m == PC_SPECTRUM_MAX_SAMPLES) {
      rc = pc_errf(e, PC_ELIMIT, "%s:%d: <spectrum> has more than %d wavelength:value pairs", file, n->line, PC_SPECTRUM_MAX_SAMPLES);
      break;
    }
    char *end;
    l[m] = strtod(p, &end);
    if (end == p || *end != ':') {
      rc = pc_errf(e, PC_EPARSE, "%s:%d: <spectrum>: '%.30s' is not wavelength:value", file, n->line, p);
      break;
    }
    p = end + 1;
    v[m] = strtod(p, &end);
    if (end == p || !(*end == 0 || *end == ' ' || *end == ',' || *end == '\t' || *end == '\n' || *end == '\r')) {
      rc = pc_errf(e, PC_EPARSE, "%s:%d: <spectrum>: '%.30s' is not wavelength:value", file, n->line, p);
      break;
    }
    if (!isfinite(l[m]) || !isfinite(v[m]) || v[m] < 0 || !(l[m] > 0)) {
      rc = pc_errf(e, PC_EINVAL, "%s:%d: <spectrum>: wavelengths must be positive and values finite and not negative", file, n->line);
      break;
    }
    p = end;
    m++;
  }
  if (!rc && pc_spectrum_sampled_rgb(l, v, m, rgb) != 0)
    rc = pc_errf(e, PC_EINVAL, "%s:%d: <spectrum>: needs at least 2 wavelengths, in increasing order", file, n->line);
  free(l);
  return rc;
}

static double srgb_to_linear(double c) {
  return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

static int color(const char *file, const pc_xml_node *n, bool signed_ok, vec3 *out, pc_err *e) {
  double v[3];
  int k = 0, rc;
  const char *val = pc_xml_attr(n, "value");
  if (strcmp(n->name, "spectrum") == 0) {
    static const char *const allowed[] = {"name", "value", "intent", NULL};
    if ((rc = pc_xml_check_attrs(file, n, allowed, e))) return rc;
    if (val && strchr(val, ':')) {
      if (pc_xml_attr(n, "intent"))
        return pc_errf(e, PC_EPARSE, "%s:%d: <spectrum>: an intent goes with a single value only", file, n->line);
      if ((rc = sampled_spectrum(file, n, val, v, e))) return rc;
    } else {
      double many[4];
      if ((rc = pc_xv_numbers(file, n, "value", val, many, 1, 4, &k, e))) return rc;
      /* Mitsuba's RGB mode: one value is grey (for an emitter, D65 scaled, which is grey in
       * RGB mode), three are the RGB values themselves */
      if (k != 1 && k != 3)
        return pc_errf(e, PC_EUNSUPPORTED, "%s:%d: <spectrum> needs 1 or 3 values, or wavelength:value pairs (Mitsuba's RGB mode)",
                       file, n->line);
      if (k == 3 && pc_xml_attr(n, "intent"))
        return pc_errf(e, PC_EPARSE, "%s:%d: <spectrum>: an intent goes with a single value only", file, n->line);
      for (int i = 0; i < 3; i++) v[i] = many[k == 3 ? i : 0];
    }  } else if (strcmp(n->name, "rgb") == 0 || strcmp(n->name, "srgb") == 0) {
    static const char *const allowed[] = {"name", "value", "intent", NULL};
    if ((rc = pc_xml_check_attrs(file, n, allowed, e))) return rc;
    const char *intent = pc_xml_attr(n, "intent");
    /* The intent only matters for spectral upsampling, which an RGB renderer never does. */
    if (intent && strcmp(intent, "reflectance") != 0 && strcmp(intent, "illuminant") != 0)
      return pc_errf(e, PC_EPARSE, "%s:%d: <%s> has an invalid intent '%s'", file, n->line, n->name, intent);
    int srgb = n->name[0] == 's';
    /* Mitsuba reads #rrggbb in both, each byte over 255: linear for <rgb>, sRGB for <srgb> */
    if (val && val[0] == '#') {
      size_t len = strlen(val);
      if (len != 7) return pc_errf(e, PC_EPARSE, "%s:%d: <%s> hex colour must be #rrggbb", file, n->line, n->name);
      for (int i = 0; i < 3; i++) {
        char hex[3] = {val[1 + 2 * i], val[2 + 2 * i], 0};
        if (!isxdigit((unsigned char)hex[0]) || !isxdigit((unsigned char)hex[1]))
          return pc_errf(e, PC_EPARSE, "%s:%d: <%s> hex colour must be #rrggbb", file, n->line, n->name);
        v[i] = (double)strtol(hex, NULL, 16) / 255.0;
      }
    } else {
      if ((rc = pc_xv_numbers(file, n, "value", val, v, 1, 3, &k, e))) return rc;
      if (k == 2) return pc_errf(e, PC_EPARSE, "%s:%d: <%s> needs 1 or 3 numbers", file, n->line, n->name);
      if (k == 1) v[1] = v[2] = v[0];
    }
    if (srgb)
      for (int i = 0; i < 3; i++) {
        if (v[i] < 0) break;
        v[i] = srgb_to_linear(v[i]);
      }
  } else if (strcmp(n->name, "blackbody") == 0) {
    static const char *const allowed[] = {"name", "temperature", "scale", NULL};
    if ((rc = pc_xml_check_attrs(file, n, allowed, e))) return rc;
    const char *t = pc_xml_attr(n, "temperature");
    if (!t) return pc_errf(e, PC_EPARSE, "%s:%d: <blackbody> lacks a temperature", file, n->line);
    char tbuf[64];
    size_t tl = strlen(t);
    if (tl >= sizeof tbuf) return pc_errf(e, PC_EPARSE, "%s:%d: <blackbody>: temperature too long", file, n->line);
    memcpy(tbuf, t, tl + 1);
    while (tl > 0 && tbuf[tl - 1] == ' ') tbuf[--tl] = 0;
    if (tl > 0 && (tbuf[tl - 1] == 'K' || tbuf[tl - 1] == 'k')) tbuf[--tl] = 0; /* "5000K", as Mitsuba allows */
    double kelvin, scale = 1;
    if ((rc = pc_xv_numbers(file, n, "temperature", tbuf, &kelvin, 1, 1, &k, e))) return rc;
    if (pc_xml_attr(n, "scale") && (rc = pc_xv_number(file, n, "scale", &scale, e))) return rc;
    if (!(kelvin >= 100 && kelvin <= 1e6))
      return pc_errf(e, PC_EINVAL, "%s:%d: <blackbody>: temperature must lie in 100..1e6 K", file, n->line);
    pc_spectrum_blackbody_rgb(kelvin, v);
    for (int i = 0; i < 3; i++) v[i] *= scale;
  } else {
    return pc_errf(e, PC_EPARSE, "%s:%d: expected <rgb>, <srgb> or <spectrum>, found <%s>", file, n->line, n->name);
  }
  for (int i = 0; i < 3; i++) {
    /* kept only where the numbers are taken as written (not through sRGB or a blackbody) */
    if (v[i] < 0 && !(signed_ok && (strcmp(n->name, "rgb") == 0 || strcmp(n->name, "spectrum") == 0)))
      return pc_errf(e, PC_EINVAL, "%s:%d: <%s> has a negative value", file, n->line, n->name);
    if (!(v[i] <= 3.4e38)) return pc_errf(e, PC_ENUMERIC, "%s:%d: <%s> value out of range", file, n->line, n->name);
  }
  *out = v3((float)v[0], (float)v[1], (float)v[2]);
  return 0;
}

int pc_xv_color(const char *file, const pc_xml_node *n, vec3 *out, pc_err *e) { return color(file, n, false, out, e); }

int pc_xv_color_signed(const char *file, const pc_xml_node *n, vec3 *out, pc_err *e) { return color(file, n, true, out, e); }

static int xyz_attrs(const char *file, const pc_xml_node *n, double def, double out[3], pc_err *e) {
  static const char *const names[3] = {"x", "y", "z"};
  for (int i = 0; i < 3; i++) {
    out[i] = def;
    if (pc_xml_attr(n, names[i])) {
      int rc = pc_xv_number(file, n, names[i], &out[i], e);
      if (rc) return rc;
    }
  }
  return 0;
}

static int vec_attr(const char *file, const pc_xml_node *n, const char *attr, double out[3], pc_err *e) {
  int k;
  return pc_xv_numbers(file, n, attr, pc_xml_attr(n, attr), out, 3, 3, &k, e);
}

static void normalize3(double v[3]) {
  double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  for (int i = 0; i < 3; i++) v[i] /= l;
}

static void cross3(const double a[3], const double b[3], double out[3]) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

static int one_transform(const char *file, const pc_xml_node *c, mat4 *t, pc_err *e) {
  static const char *const xyz[] = {"x", "y", "z", NULL};
  static const char *const rot[] = {"x", "y", "z", "angle", NULL};
  static const char *const scl[] = {"x", "y", "z", "value", NULL};
  static const char *const mat[] = {"value", NULL};
  static const char *const look[] = {"origin", "target", "up", NULL};
  double v[16];
  int rc, k;
  *t = mat4_identity();
  if (c->first) return pc_errf(e, PC_EPARSE, "%s:%d: <%s> must be empty", file, c->line, c->name);
  if (strcmp(c->name, "translate") == 0) {
    /* Mitsuba 2's form, which some converters write into 0.6 scenes; Mitsuba 0.6's schema refuses it */
    if (pc_xml_attr(c, "value"))
      return pc_errf(e, PC_EPARSE, "%s:%d: <translate value=...> is Mitsuba 2's form: Mitsuba 0.6 takes x, y, z", file, c->line);
    if ((rc = pc_xml_check_attrs(file, c, xyz, e)) || (rc = xyz_attrs(file, c, 0, v, e))) return rc;
    for (int i = 0; i < 3; i++) t->m[i][3] = v[i];
  } else if (strcmp(c->name, "scale") == 0) {
    if ((rc = pc_xml_check_attrs(file, c, scl, e))) return rc;
    if (pc_xml_attr(c, "value")) {
      if (pc_xml_attr(c, "x") || pc_xml_attr(c, "y") || pc_xml_attr(c, "z"))
        return pc_errf(e, PC_EPARSE, "%s:%d: <scale> takes either value or x, y, z", file, c->line);
      if ((rc = pc_xv_number(file, c, "value", &v[0], e))) return rc;
      v[1] = v[2] = v[0];
    } else if ((rc = xyz_attrs(file, c, 1, v, e))) {
      return rc;
    }
    for (int i = 0; i < 3; i++) t->m[i][i] = v[i];
  } else if (strcmp(c->name, "rotate") == 0) {
    double ang;
    if ((rc = pc_xml_check_attrs(file, c, rot, e)) || (rc = xyz_attrs(file, c, 0, v, e)) ||
        (rc = pc_xv_number(file, c, "angle", &ang, e)))
      return rc;
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(l > 0) || !isfinite(l)) return pc_errf(e, PC_EINVAL, "%s:%d: <rotate> has a zero axis", file, c->line);
    double x = v[0] / l, y = v[1] / l, z = v[2] / l;
    double s = sin(ang * 3.14159265358979323846 / 180.0), co = cos(ang * 3.14159265358979323846 / 180.0);
    /* Rodrigues' formula, right-handed (Mitsuba's Transform::rotate). */
    double r[3][3] = {{x * x + (1 - x * x) * co, x * y * (1 - co) - z * s, x * z * (1 - co) + y * s},
                      {x * y * (1 - co) + z * s, y * y + (1 - y * y) * co, y * z * (1 - co) - x * s},
                      {x * z * (1 - co) - y * s, y * z * (1 - co) + x * s, z * z + (1 - z * z) * co}};
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) t->m[i][j] = r[i][j];
  } else if (strcmp(c->name, "matrix") == 0) {
    if ((rc = pc_xml_check_attrs(file, c, mat, e)) ||
        (rc = pc_xv_numbers(file, c, "value", pc_xml_attr(c, "value"), v, 16, 16, &k, e)))
      return rc;
    for (int i = 0; i < 16; i++) t->m[i / 4][i % 4] = v[i];
    if (v[12] != 0 || v[13] != 0 || v[14] != 0 || v[15] != 1)
      return pc_errf(e, PC_EUNSUPPORTED, "%s:%d: <matrix> must be affine (last row 0 0 0 1)", file, c->line);
  } else if (strcmp(c->name, "lookat") == 0 || strcmp(c->name, "lookAt") == 0) {
    double o[3], tg[3], up[3], dir[3], left[3], nup[3];
    const char *up_text = pc_xml_attr(c, "up");
    bool up_given = up_text && strspn(up_text, ", \t\r\n") < strlen(up_text);
    if ((rc = pc_xml_check_attrs(file, c, look, e)) || (rc = vec_attr(file, c, "origin", o, e)) ||
        (rc = vec_attr(file, c, "target", tg, e)) || (up_given && (rc = vec_attr(file, c, "up", up, e))))
      return rc;
    for (int i = 0; i < 3; i++) dir[i] = tg[i] - o[i];
    double dl = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    if (!(dl > 0) || !isfinite(dl)) return pc_errf(e, PC_EINVAL, "%s:%d: <lookat> origin equals target", file, c->line);
    normalize3(dir);
    /* Without an up (or with a zero one) Mitsuba takes the first axis of its coordinateSystem
       about the view direction, which fixes the image's roll. */
    if (!up_given || (up[0] == 0 && up[1] == 0 && up[2] == 0)) {
      frame f = frame_mitsuba(v3((float)dir[0], (float)dir[1], (float)dir[2]));
      up[0] = f.s.x, up[1] = f.s.y, up[2] = f.s.z;
    }
    cross3(up, dir, left);
    double ll = sqrt(left[0] * left[0] + left[1] * left[1] + left[2] * left[2]);
    /* only an exactly parallel up is refused, as Mitsuba's normalizeStrict does: a scene
       generator's up 4e-7 away from the view direction still gives a camera there */
    if (!(ll > 0) || !isfinite(ll))
      return pc_errf(e, PC_EINVAL, "%s:%d: <lookat> up is parallel to the view direction", file, c->line);
    normalize3(left);
    cross3(dir, left, nup);
    for (int i = 0; i < 3; i++) {
      t->m[i][0] = left[i];
      t->m[i][1] = nup[i];
      t->m[i][2] = dir[i];
      t->m[i][3] = o[i];
    }
  } else {
    return pc_errf(e, PC_EUNSUPPORTED, "%s:%d: unknown transform element <%s>", file, c->line, c->name);
  }
  return 0;
}

int pc_xv_transform(const char *file, const pc_xml_node *n, mat4 *out, pc_err *e) {
  mat4 m = mat4_identity();
  for (const pc_xml_node *c = n->first; c; c = c->next) {
    mat4 t;
    int rc = one_transform(file, c, &t, e);
    if (rc) return rc;
    m = mat4_mul(&t, &m);
    for (int i = 0; i < 4; i++)
      for (int j = 0; j < 4; j++)
        if (!isfinite(m.m[i][j]) || fabs(m.m[i][j]) > 1e30)
          return pc_errf(e, PC_ENUMERIC, "%s:%d: <%s> makes the transform non-finite", file, c->line, c->name);
  }
  mat4 inv;
  if (!mat4_inverse(&m, &inv)) return pc_errf(e, PC_EINVAL, "%s:%d: <transform> is singular", file, n->line);
  *out = m;
  return 0;
}

bool pc_xv_ior_name(const char *name, float *out) {
  /* Mitsuba's table (Hecht, Optics; 0-20 degrees Celsius at ~589 nm). */
  static const struct { const char *name; float ior; } tab[] = {
      {"vacuum", 1.0f},          {"helium", 1.000036f},     {"hydrogen", 1.000132f},
      {"air", 1.000277f},        {"carbon dioxide", 1.00045f}, {"water", 1.3330f},
      {"acetone", 1.36f},        {"ethanol", 1.361f},       {"carbon tetrachloride", 1.461f},
      {"glycerol", 1.4729f},     {"benzene", 1.501f},       {"silicone oil", 1.52045f},
      {"bromine", 1.661f},       {"water ice", 1.31f},      {"fused quartz", 1.458f},
      {"pyrex", 1.470f},         {"acrylic glass", 1.49f},  {"polypropylene", 1.49f},
      {"bk7", 1.5046f},          {"sodium chloride", 1.544f}, {"amber", 1.55f},
      {"pet", 1.5750f},          {"diamond", 2.419f},
  };
  for (size_t i = 0; i < sizeof tab / sizeof tab[0]; i++)
    if (strcasecmp(name, tab[i].name) == 0) {
      *out = tab[i].ior;
      return true;
    }
  return false;
}
