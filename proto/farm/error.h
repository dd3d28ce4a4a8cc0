// Errors of the farm's wire layer: malformed or inconsistent data from another process (a corrupt
// payload, a bundle entry that leaves its bundle, a spec outside the limits). The services turn them
// into INVALID_ARGUMENT replies; they never terminate a process.
#pragma once
#include <stdexcept>
#include <string>

namespace pf::farm {

class FarmError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

}  // namespace pf::farm
