/* main.c: pcbpt-coord entry point (verbs are added as they land). */
#include <stdio.h>
int main(void) {
  fprintf(stderr, "pcbpt-coord: not yet functional\n");
  return 2;
}
