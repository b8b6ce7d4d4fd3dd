/* See guard.c. */
#include <mujoco/mujoco.h>

void bp_error_handler(const char *msg);
const char *bp_last_error(void);
int bp_step(const mjModel *m, mjData *d);
int bp_forward(const mjModel *m, mjData *d);
int bp_kinematics(const mjModel *m, mjData *d, int contacts);
int bp_reset_data(const mjModel *m, mjData *d);
int bp_copy_data(mjData *dest, const mjModel *m, const mjData *src);
int bp_make_data(const mjModel *m, mjData **out);
int bp_copy_model(const mjModel *m, mjModel **out);
