#pragma once
// Angle constants shared by the cameras, the job paths and the procedural scenes.

namespace aperture {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kRadPerDeg = kPi / 180.0;  ///< degrees -> radians
inline constexpr double kDegPerRad = 180.0 / kPi;  ///< radians -> degrees

}  // namespace aperture
