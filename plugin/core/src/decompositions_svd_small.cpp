// The SVDs decompositions.hpp declares extern: the 2 x 2 and 2 x 3 shapes.
#include "uhaptics/core/decompositions.hpp"

template class Eigen::JacobiSVD<uhaptics::Mat<2, 2>>;
template class Eigen::JacobiSVD<uhaptics::Mat<2, 3>>;
template class Eigen::JacobiSVD<uhaptics::Mat<3, 2>>;
