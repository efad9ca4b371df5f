// The parameter loader is include/omni_base/param_loader.h (the motor board harness uses it too); the
// node sources include it by this name.
#pragma once
#include "omni_base/param_loader.h"
