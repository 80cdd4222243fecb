#include "render_storage.h"

#include <algorithm>
#include <cstdint>
#include <memory>

#include "aov_arrays.h"
#include "core/aov/aov_table.h"
#include "core/util/error.h"
#include "core/util/huge_pages.h"
#include "core/util/spelling.h"

namespace aperture::python {

namespace nb = nanobind;

namespace {

std::string shapeText(const std::vector<size_t>& shape) {
  std::string s = "(";
  for (size_t k = 0; k < shape.size(); ++k)
    s += std::to_string(shape[k]) + (shape.size() == 1 ? "," : k + 1 < shape.size() ? ", " : "");
  return s + ")";
}

/// The data of `value`, the caller's array for AOV `c`, once it is checked to be a writeable,
/// C-contiguous NumPy array of the layout `l` and the channel's dtype (read through NumPy's own
/// attributes).
void* checkedArray(const char* what, const PixelChannel& c, const ArrayLayout& l,
                   nb::handle value) {
  const std::string dtypeName = c.isFloat ? "float32" : "uint32";
  const std::string need = cat("this render writes '", c.name, "' as a C-contiguous ", dtypeName,
                               " array of shape ", shapeText(l.shape));
  const auto fail = [&](const std::string& got) -> void* {
    throw nb::value_error(cat(what, ": out['", c.name, "'] ", got, "; ", need).c_str());
  };
  const nb::module_ numpy = nb::module_::import_("numpy");
  if (!nb::isinstance(value, numpy.attr("ndarray")))
    return fail(
        cat("is a ", nb::str(value.type().attr("__name__")).c_str(), ", not a NumPy array"));
  const nb::object dtype = value.attr("dtype"), shape = value.attr("shape");
  const std::string got =
      cat("has shape ", nb::str(shape).c_str(), " and dtype ", nb::str(dtype).c_str());
  if (!dtype.equal(numpy.attr("dtype")(dtypeName.c_str()))) return fail(got);
  bool sameShape = nb::len(shape) == l.shape.size();
  for (size_t k = 0; sameShape && k < l.shape.size(); ++k)
    sameShape = nb::cast<size_t>(shape[k]) == l.shape[k];
  if (!sameShape) return fail(got);
  const nb::object flags = value.attr("flags");
  if (!nb::cast<bool>(flags.attr("c_contiguous"))) return fail(got + ", not C-contiguous");
  if (!nb::cast<bool>(flags.attr("writeable"))) return fail("is read-only");
  const nb::object data = value.attr("__array_interface__")["data"];
  return reinterpret_cast<void*>(nb::cast<uintptr_t>(data[0]));
}

/// Throws when two of the given arrays share memory: the render would write both.
void checkDisjoint(const char* what, const FramePixels& px,
                   const std::vector<std::pair<std::string, nb::object>>& given) {
  struct Span {
    const char* begin;
    const char* end;
    const std::string* name;
  };
  std::vector<Span> spans;
  for (const auto& [name, array] : given) {
    const PixelChannel& c = *px.find(name);
    const char* begin = static_cast<const char*>(c.data);
    spans.push_back({begin, begin + sizeof(uint32_t) * c.valueCount(px.pixelCount()), &name});
  }
  std::sort(spans.begin(), spans.end(),
            [](const Span& a, const Span& b) { return a.begin < b.begin; });
  for (size_t k = 1; k < spans.size(); ++k)
    if (spans[k].begin < spans[k - 1].end)
      throw nb::value_error(cat(what, ": out['", *spans[k - 1].name, "'] and out['", *spans[k].name,
                                "'] share memory; each AOV needs its own array")
                                .c_str());
}

/// Storage for frame arrays that nothing has written: one LargeBuffer block per channel
/// (core/util/huge_pages.h: from 2 MB up on a 2 MB boundary, advised onto huge pages, its
/// resize leaving the values unwritten), so that the render threads are the first to touch its
/// pages. Freed with the last array.
class UnwrittenStorage {
 public:
  /// `bytes` bytes (a multiple of 4), unwritten.
  void* allocate(size_t bytes) { return blocks_.emplace_back(bytes / sizeof(uint32_t)).data(); }

 private:
  std::vector<LargeBuffer<uint32_t>> blocks_;
};

/// A capsule owning `storage`: the owner handed to channelArray.
nb::capsule ownerOf(std::unique_ptr<UnwrittenStorage> storage) {
  return nb::capsule(storage.release(),
                     [](void* p) noexcept { delete static_cast<UnwrittenStorage*>(p); });
}

std::vector<std::string> channelNames(const FramePixels& px) {
  std::vector<std::string> names;
  for (const PixelChannel& c : px.channels) names.push_back(c.name);
  return names;
}

}  // namespace

RenderStorage renderStorage(int width, int height, const AovSet& aovs, size_t frames,
                            nb::handle out, const char* what) {
  RenderStorage s;
  s.pixels = unboundPixels(width, height, aovs);
  if (!out.is_none()) {
    if (!nb::isinstance<nb::dict>(out))
      throw nb::type_error(cat(what, ": out must be a dict of AOV name -> array").c_str());
    for (auto [key, value] : nb::borrow<nb::dict>(out)) {
      const std::string name = nb::str(key).c_str();
      const PixelChannel* c = s.pixels.find(name);
      if (!c) {
        const std::vector<std::string> names = channelNames(s.pixels);
        throw nb::value_error(cat(what, ": out['", name, "'] is not an AOV of this render",
                                  didYouMean(name, names), " (it renders: ", join(names, ", "), ")")
                                  .c_str());
      }
      if (isLayerAovName(name))
        throw nb::value_error(
            cat(what, ": out['", name, "']: layered hits are not written into given arrays")
                .c_str());
      const_cast<PixelChannel*>(c)->data =
          checkedArray(what, *c, layoutOf(s.pixels, *c, frames), value);
      s.given.emplace_back(name, nb::borrow(value));
    }
    checkDisjoint(what, s.pixels, s.given);
  }
  auto fresh = std::make_unique<UnwrittenStorage>();
  bool any = false;
  for (PixelChannel& c : s.pixels.channels)
    if (!c.data) {
      c.data = fresh->allocate(sizeof(uint32_t) * c.valueCount(s.pixels.pixelCount()));
      any = true;
    }
  s.owner = any ? nb::object(ownerOf(std::move(fresh))) : nb::none();
  return s;
}

nb::dict renderedArrays(const RenderStorage& storage, size_t frames) {
  // In the channels' order, as a render without out= gives them.
  nb::dict out;
  for (const PixelChannel& c : storage.pixels.channels) {
    const auto given = std::find_if(storage.given.begin(), storage.given.end(),
                                    [&](const auto& g) { return g.first == c.name; });
    out[c.name.c_str()] = given != storage.given.end()
                              ? given->second
                              : channelArray(storage.pixels, c, frames, storage.owner);
  }
  return out;
}

}  // namespace aperture::python
