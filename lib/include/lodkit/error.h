#pragma once
// lodkit's one error strategy: every failure the caller can act on is a lodkit::Error whose message
// names the file or parameter and what is wrong with it ("bunny.ply: line 12: face index 40 out of
// range (file has 35 vertices)"). The CLI prints it as "lodkit: error: <message>" and exits 1.
#include <stdexcept>
#include <string>

namespace lodkit {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace lodkit
