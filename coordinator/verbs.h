/* verbs.h: the sub-commands of pcbpt-coord. Each takes the arguments after the verb and
 * returns the process exit status. */
#ifndef PC_VERBS_H
#define PC_VERBS_H

int pc_cmd_render(int argc, char **argv);
int pc_cmd_compare(int argc, char **argv);
/* The farm (coordinator/serve.c, coordinator/cmd_client.c). */
int pc_cmd_serve(int argc, char **argv);
int pc_cmd_submit(int argc, char **argv);
int pc_cmd_status(int argc, char **argv);
int pc_cmd_list(int argc, char **argv);
int pc_cmd_workers(int argc, char **argv);
int pc_cmd_wait(int argc, char **argv);
int pc_cmd_cancel(int argc, char **argv);
int pc_cmd_fetch(int argc, char **argv);

#endif
