/* study_report.h: the study's self-contained HTML report (DIR/report.html): per scene the
 * charts, every method's image side by side with the reference, a zoomed crop of the noisiest
 * region and the tables, every image inlined as a data: URI so the one file can be opened in a
 * browser or put in a paper's supplement. */
#ifndef PC_STUDY_REPORT_H
#define PC_STUDY_REPORT_H

#include <stdbool.h>
#include <stdio.h>

#include "error.h"
#include "render.h"
#include "study.h"

typedef struct pc_report {
  FILE *f;
  char path[4096], tmp[4200];
} pc_report;

typedef struct pc_report_scene {
  const char *name, *path;     /* the scene's name and file */
  const char *dir;             /* its study folder: <method>.exr/.png, study_*.svg */
  const char *tables;          /* the printed tables */
  const float *reference;      /* the reference's beauty (w*h*3), NULL: estimated errors */
  int w, h;
  const pc_study_method *methods;
  int nmethods;
  bool scaling, inner, shares; /* study_scaling.svg, study_inner.svg, study_shares.svg were written */
  bool iterations;             /* study_iterations.svg was written */
} pc_report_scene;

int pc_report_begin(pc_report *r, const char *path, pc_err *e);
/* Also writes <dir>/reference.png and <dir>/crop_<name>.png (the crops it shows). */
int pc_report_add_scene(pc_report *r, const pc_report_scene *s, pc_err *e);
/* Closes the document and renames it into place. */
int pc_report_end(pc_report *r, pc_err *e);
void pc_report_abandon(pc_report *r);

#endif
