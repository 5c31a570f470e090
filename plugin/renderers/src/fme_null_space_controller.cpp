// Explicit instantiations for the shipped planar linkages (compile-time check of the template and
// shorter builds for users of these two devices).
#include "uhaptics/renderers/fme_null_space_controller.hpp"

#include "uhaptics/models/planar_linkage_model.hpp"

namespace uhaptics {
template class FmeNullSpaceController<Rhi4Model>;
template class FmeNullSpaceController<Planar3Model>;
}  // namespace uhaptics
