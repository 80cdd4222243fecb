// Placeholder until the sign helper lands (branch query-sign replaces this file).
#include "core/queries/inside.h"

#include "core/util/error.h"

namespace aperture {

const char* insideMethodName(InsideMethod method) {
  switch (method) {
    case InsideMethod::Parity:
      return "parity";
    case InsideMethod::Winding:
      return "winding";
    default:
      return "automatic";
  }
}

InsideMethod parseInsideMethod(const std::string& name) {
  if (name == "parity") return InsideMethod::Parity;
  if (name == "winding") return InsideMethod::Winding;
  if (name == "automatic") return InsideMethod::Automatic;
  throw Error("unknown inside method '" + name + "' (parity, winding, automatic)");
}

ClosedCheck checkClosed(const Scene&) { throw Error("checkClosed: not built yet"); }

InsideResult insideOf(const Scene&, const double*, size_t, const InsideOptions&) {
  throw Error("insideOf: not built yet");
}

}  // namespace aperture
