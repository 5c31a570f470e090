#pragma once
// CHAI3D's vectors and the plugin's Eigen vectors: the same three components in the same frame.
#include "math/CVector3d.h"
#include "uhaptics/core/types.hpp"

namespace chai3d {

inline uhaptics::Vec3 toEigen(const cVector3d& a_v) { return uhaptics::Vec3(a_v(0), a_v(1), a_v(2)); }
inline cVector3d toChai(const uhaptics::Vec3& a_v) { return cVector3d(a_v(0), a_v(1), a_v(2)); }

}  // namespace chai3d
