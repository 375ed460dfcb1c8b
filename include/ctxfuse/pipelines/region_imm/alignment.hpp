// How the region pipeline's filters start without truth: dynamic alignment from position
// fixes, GNSS fixes or, where no GNSS reaches (a drive that starts in a garage), UWB snapshot
// multilaterations (models/planar_start.hpp: the aligner's options and the initial belief from
// Settings, which is a models::PlanarStartSettings).
#pragma once

#include "ctxfuse/models/alignment.hpp"
#include "ctxfuse/models/planar_start.hpp"
#include "ctxfuse/pipelines/region_imm/settings.hpp"

namespace ctxfuse::pipelines::region_imm {

/// Position, velocity and heading at time t (models/alignment.hpp).
using Alignment = models::PlanarAlignment;
using models::KnownMotion;

}  // namespace ctxfuse::pipelines::region_imm
