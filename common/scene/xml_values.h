/* xml_values.h: the value syntax of Mitsuba 0.6 scene files: number lists, colours
 * (<rgb>, <srgb>, <spectrum>), <transform> elements and named indices of refraction. Every
 * function reports "file:line: <element> ..." on malformed, non-finite or unsupported input. */
#ifndef PC_XML_VALUES_H
#define PC_XML_VALUES_H

#include "error.h"
#include "vecmath.h"
#include "xml_tree.h"

/* Parses between min and max finite numbers separated by commas and/or whitespace. */
int pc_xv_numbers(const char *file, const pc_xml_node *n, const char *attr, const char *s, double *out,
                  int min, int max, int *count, pc_err *e);
/* One finite number from attribute `attr` of n (required). */
int pc_xv_number(const char *file, const pc_xml_node *n, const char *attr, double *out, pc_err *e);
/* An <rgb>, <srgb> or <spectrum> element as linear RGB; negative values are errors. */
int pc_xv_color(const char *file, const pc_xml_node *n, vec3 *out, pc_err *e);
/* The same, keeping negative values of <rgb> and of <spectrum> given as 1 or 3 numbers (Mitsuba's
 * RGB mode stores them as written); for parameters whose meaning is defined for them. */
int pc_xv_color_signed(const char *file, const pc_xml_node *n, vec3 *out, pc_err *e);
/* A <transform> element: its children applied in order (M = T_new * M). */
int pc_xv_transform(const char *file, const pc_xml_node *n, mat4 *out, pc_err *e);
/* Mitsuba's named indices of refraction (case-insensitive); false if unknown. */
bool pc_xv_ior_name(const char *name, float *out);

#endif
