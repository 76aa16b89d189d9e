/* verbs.h: the sub-commands of pcbpt-coord. Each takes the arguments after the verb and
 * returns the process exit status. */
#ifndef PC_VERBS_H
#define PC_VERBS_H

int pc_cmd_render(int argc, char **argv);
int pc_cmd_compare(int argc, char **argv);

#endif
