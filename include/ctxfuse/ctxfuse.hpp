// Umbrella header: the engine core, filters, policies and models.
#pragma once

#include "ctxfuse/core/block_sparsity.hpp"
#include "ctxfuse/core/concepts.hpp"
#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/core/layout.hpp"
#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/so3.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"
#include "ctxfuse/core/validation.hpp"
#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/models/ins.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/models/linear.hpp"
#include "ctxfuse/models/on_layout.hpp"
#include "ctxfuse/policies/gating.hpp"
