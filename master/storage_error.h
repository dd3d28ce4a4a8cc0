// The master's storage failed: a full disk, an unwritable or damaged data directory or store. The request
// is worth repeating once the fault is cleared, so the services answer UNAVAILABLE (services.cpp), and
// workers and clients retry instead of dropping their work.
#pragma once
#include <stdexcept>

namespace pf::master {

struct StorageError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

}  // namespace pf::master
