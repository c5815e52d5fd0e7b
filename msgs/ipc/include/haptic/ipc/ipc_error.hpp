#pragma once

#include <stdexcept>
#include <string>

namespace haptic::ipc {

// Thrown while a process sets up its transports (never on the RT path). what() is one line
// a user can act on: which broker or profile is missing and how to start or fix it.
class IpcError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

}  // namespace haptic::ipc
