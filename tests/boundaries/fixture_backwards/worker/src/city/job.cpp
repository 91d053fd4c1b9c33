// Fixture for the boundary check: a city job that includes the queue loop's header (an include
// running back up). The check must reject this file.
#include "csgtile/worker/run.h"
