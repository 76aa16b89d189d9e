/* xml_tree.h: a small element tree read from an untrusted XML file with expat (elements,
 * attributes and line numbers; no text content), bounded in file size, depth and element
 * count. The scene loader interprets it. */
#ifndef PC_XML_TREE_H
#define PC_XML_TREE_H

#include <stddef.h>

#include "error.h"

#define PC_XML_MAX_FILE ((size_t)64 << 20)
#define PC_XML_MAX_DEPTH 64
#define PC_XML_MAX_ELEMENTS (1 << 22)

typedef struct pc_xml_node {
  char *name;
  int line;
  const char *file;  /* set by the scene loader on elements spliced in by <include>; NULL: the
                        main file (not owned) */
  int nattrs;
  char **attrs; /* 2*nattrs strings: name, value, ... */
  struct pc_xml_node *first, *next; /* children, siblings (document order) */
} pc_xml_node;

/* Parses `path`; messages name the file as `display`. */
int pc_xml_parse(const char *path, const char *display, pc_xml_node **root, pc_err *e);
void pc_xml_free(pc_xml_node *root);
/* Value of an attribute, or NULL. */
const char *pc_xml_attr(const pc_xml_node *n, const char *name);
/* Fails naming the first attribute of n not in the NULL-terminated list `allowed`. */
int pc_xml_check_attrs(const char *display, const pc_xml_node *n, const char *const *allowed, pc_err *e);

#endif
