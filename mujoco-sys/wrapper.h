#include <mujoco/mujoco.h>
#include "guard.h"
