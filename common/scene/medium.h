// Participating media. Declared here so that shapes can carry interior/exterior media from the start;
// homogeneous media and phase functions arrive with the path-space layer (issue 4).
#pragma once
#include "scene/object.h"

namespace pf {

class Medium : public Object {};

}  // namespace pf
