/* xml_tree.c: builds the bounded element tree of xml_tree.h with expat. Document type
 * declarations are refused outright, so no entity can expand. */
#include "xml_tree.h"

#include <expat.h>
#include <stdlib.h>
#include <string.h>

#include "file_read.h"

typedef struct build {
  XML_Parser p;
  const char *display;
  pc_xml_node *root;
  pc_xml_node *stack[PC_XML_MAX_DEPTH];
  pc_xml_node *last[PC_XML_MAX_DEPTH]; /* last child of each open element */
  int depth;
  long count;
  int rc;
  pc_err *e;
} build;

static void fail(build *b, int code, const char *what) {
  if (b->rc) return;
  b->rc = pc_errf(b->e, code, "%s:%lu: %s", b->display, (unsigned long)XML_GetCurrentLineNumber(b->p), what);
  XML_StopParser(b->p, XML_FALSE);
}

static void node_free(pc_xml_node *n) {
  while (n) {
    pc_xml_node *next = n->next;
    node_free(n->first); /* recursion bounded by PC_XML_MAX_DEPTH */
    free(n->name);
    for (int i = 0; i < 2 * n->nattrs; i++) free(n->attrs[i]);
    free(n->attrs);
    free(n);
    n = next;
  }
}

static void XMLCALL on_start(void *ud, const XML_Char *name, const XML_Char **atts) {
  build *b = ud;
  if (b->rc) return;
  if (b->depth >= PC_XML_MAX_DEPTH) return fail(b, PC_ELIMIT, "elements nested too deeply");
  if (++b->count > PC_XML_MAX_ELEMENTS) return fail(b, PC_ELIMIT, "too many elements");
  if (b->depth == 0 && b->root) return fail(b, PC_EPARSE, "more than one root element");
  pc_xml_node *n = calloc(1, sizeof *n);
  if (!n) return fail(b, PC_ENOMEM, "out of memory");
  int na = 0;
  while (atts[2 * na]) na++;
  n->name = strdup(name);
  n->attrs = calloc((size_t)(2 * na + 1), sizeof *n->attrs);
  n->line = (int)XML_GetCurrentLineNumber(b->p);
  int ok = n->name && n->attrs;
  for (int i = 0; ok && i < 2 * na; i++) {
    n->attrs[i] = strdup(atts[i]);
    ok = n->attrs[i] != NULL;
    n->nattrs = (i + 2) / 2;
  }
  if (!ok) {
    node_free(n);
    return fail(b, PC_ENOMEM, "out of memory");
  }
  if (b->depth == 0) b->root = n;
  else if (b->last[b->depth - 1]) b->last[b->depth - 1]->next = n;
  else b->stack[b->depth - 1]->first = n;
  if (b->depth > 0) b->last[b->depth - 1] = n;
  b->stack[b->depth] = n;
  b->last[b->depth] = NULL;
  b->depth++;
}

static void XMLCALL on_end(void *ud, const XML_Char *name) {
  (void)name;
  build *b = ud;
  if (!b->rc) b->depth--;
}

static void XMLCALL on_text(void *ud, const XML_Char *s, int len) {
  build *b = ud;
  for (int i = 0; i < len; i++)
    if (!(s[i] == ' ' || s[i] == '\t' || s[i] == '\r' || s[i] == '\n'))
      return fail(b, PC_EPARSE, "unexpected text content (values go in attributes)");
}

static void XMLCALL on_doctype(void *ud, const XML_Char *name, const XML_Char *sysid, const XML_Char *pubid,
                               int has_internal) {
  (void)name, (void)sysid, (void)pubid, (void)has_internal;
  fail(ud, PC_EUNSUPPORTED, "document type declarations (<!DOCTYPE>) are not supported");
}

int pc_xml_parse(const char *path, const char *display, pc_xml_node **root, pc_err *e) {
  *root = NULL;
  char *buf;
  size_t len;
  int rc = pc_file_read(path, PC_XML_MAX_FILE, &buf, &len, e);
  if (rc) return rc;
  build b = {.display = display, .e = e};
  b.p = XML_ParserCreate(NULL);
  if (!b.p) {
    free(buf);
    return pc_errf(e, PC_ENOMEM, "%s: cannot create the XML parser", display);
  }
  XML_SetUserData(b.p, &b);
  XML_SetElementHandler(b.p, on_start, on_end);
  XML_SetCharacterDataHandler(b.p, on_text);
  XML_SetStartDoctypeDeclHandler(b.p, on_doctype);
  if (XML_Parse(b.p, buf, (int)len, XML_TRUE) == XML_STATUS_ERROR && !b.rc)
    b.rc = pc_errf(e, PC_EPARSE, "%s:%lu: XML syntax error: %s", display,
                   (unsigned long)XML_GetCurrentLineNumber(b.p), XML_ErrorString(XML_GetErrorCode(b.p)));
  if (!b.rc && !b.root) b.rc = pc_errf(e, PC_EPARSE, "%s: no root element", display);
  XML_ParserFree(b.p);
  free(buf);
  if (b.rc) {
    node_free(b.root);
    return b.rc;
  }
  *root = b.root;
  return 0;
}

void pc_xml_free(pc_xml_node *root) { node_free(root); }

const char *pc_xml_attr(const pc_xml_node *n, const char *name) {
  for (int i = 0; i < n->nattrs; i++)
    if (strcmp(n->attrs[2 * i], name) == 0) return n->attrs[2 * i + 1];
  return NULL;
}

int pc_xml_check_attrs(const char *display, const pc_xml_node *n, const char *const *allowed, pc_err *e) {
  for (int i = 0; i < n->nattrs; i++) {
    int ok = 0;
    for (const char *const *a = allowed; *a && !ok; a++) ok = strcmp(*a, n->attrs[2 * i]) == 0;
    if (!ok)
      return pc_errf(e, PC_EPARSE, "%s:%d: unknown attribute '%s' on <%s>", display, n->line, n->attrs[2 * i], n->name);
  }
  return 0;
}
