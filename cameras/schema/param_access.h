#pragma once
// fieldAccess<&CameraParams::member>(): the get/set pair of a ParamSpec for a plain or
// std::optional member of a common type. Included by cameras/schema/param_schema.h.
#include <optional>
#include <type_traits>
#include <variant>

namespace aperture {

namespace param_detail {
template <class T>
struct IsOptional : std::false_type {};
template <class T>
struct IsOptional<std::optional<T>> : std::true_type {};
}  // namespace param_detail

template <auto Member>
ParamAccess fieldAccess() {
  using Field = std::remove_reference_t<decltype(std::declval<CameraParams&>().*Member)>;
  ParamAccess a;
  a.get = [](const CameraParams& p) -> std::optional<ParamValue> {
    if constexpr (param_detail::IsOptional<Field>::value) {
      if (!(p.*Member)) return std::nullopt;
      return ParamValue(*(p.*Member));
    } else {
      return ParamValue(p.*Member);
    }
  };
  a.set = [](CameraParams& p, const ParamValue& v) {
    if constexpr (param_detail::IsOptional<Field>::value)
      p.*Member = std::get<typename Field::value_type>(v);
    else
      p.*Member = std::get<Field>(v);
  };
  return a;
}

}  // namespace aperture
