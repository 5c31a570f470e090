// The SVDs decompositions.hpp declares extern: the 2 x 4 shapes.
#include "uhaptics/core/decompositions.hpp"

template class Eigen::JacobiSVD<uhaptics::Mat<2, 4>>;
template class Eigen::JacobiSVD<uhaptics::Mat<4, 2>>;
