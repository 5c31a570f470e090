// The SVDs decompositions.hpp declares extern: 6 x 6 (the TAU's Jacobians).
#include "uhaptics/core/decompositions.hpp"

template class Eigen::JacobiSVD<uhaptics::Mat<6, 6>>;
