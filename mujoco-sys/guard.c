/* Fatal MuJoCo errors that return instead of ending the process.
 *
 * MuJoCo reports a fatal error by calling mju_user_error and expects it not to return. The
 * handler here jumps back (longjmp) to the innermost bp_* call of the same thread, which then
 * returns 1 with the message kept for bp_last_error; outside such a call it prints the message
 * and exits, as MuJoCo's default handler does. The jump crosses MuJoCo's C frames and this
 * file's only: no Rust frame lies between setjmp and longjmp. After an error the mjData is in
 * an unspecified state until it is reset or overwritten (mj_resetData / mj_copyData).
 */
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <mujoco/mujoco.h>

static _Thread_local jmp_buf *bp_guard = NULL;
static _Thread_local char bp_message[1024];

void bp_error_handler(const char *msg) {
    if (bp_guard != NULL) {
        snprintf(bp_message, sizeof bp_message, "%s", msg != NULL ? msg : "(no message)");
        longjmp(*bp_guard, 1);
    }
    fprintf(stderr, "MuJoCo fatal error: %s\n", msg != NULL ? msg : "(no message)");
    exit(2);
}

const char *bp_last_error(void) { return bp_message; }

/* Runs BODY with the guard set; 0 on success, 1 after a fatal error. */
#define GUARDED(BODY)                                                                              \
    do {                                                                                           \
        jmp_buf here;                                                                              \
        jmp_buf *volatile outer = bp_guard;                                                        \
        if (setjmp(here) != 0) {                                                                   \
            bp_guard = outer;                                                                      \
            return 1;                                                                              \
        }                                                                                          \
        bp_guard = &here;                                                                          \
        BODY;                                                                                      \
        bp_guard = outer;                                                                          \
        return 0;                                                                                  \
    } while (0)

int bp_step(const mjModel *m, mjData *d) { GUARDED(mj_step(m, d)); }

int bp_forward(const mjModel *m, mjData *d) { GUARDED(mj_forward(m, d)); }

int bp_kinematics(const mjModel *m, mjData *d, int contacts) {
    GUARDED({
        mj_kinematics(m, d);
        mj_comPos(m, d);
        if (contacts) mj_collision(m, d);
        mj_comVel(m, d);
    });
}

int bp_reset_data(const mjModel *m, mjData *d) { GUARDED(mj_resetData(m, d)); }

int bp_copy_data(mjData *dest, const mjModel *m, const mjData *src) { GUARDED(mj_copyData(dest, m, src)); }

int bp_make_data(const mjModel *m, mjData **out) {
    *out = NULL;
    GUARDED(*out = mj_makeData(m));
}

int bp_copy_model(const mjModel *m, mjModel **out) {
    *out = NULL;
    GUARDED(*out = mj_copyModel(NULL, m));
}
