#pragma once
// Colours of the house style: a qualitative palette for series and the perceptual colour maps
// (turbo, viridis) for values, both as 8-bit RGB.
#include <array>
#include <cstdint>
#include <string>

namespace mppi::plot {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb&) const = default;
};

inline constexpr Rgb kBlack{20, 20, 20};
inline constexpr Rgb kGrey{128, 128, 128};
inline constexpr Rgb kLightGrey{190, 190, 190};
inline constexpr Rgb kGridGrey{225, 225, 225};
inline constexpr Rgb kWhite{255, 255, 255};

// Series colour i (Tableau 10 order: blue, orange, green, red, purple, brown, pink, grey, olive,
// cyan), repeating.
Rgb palette(int i);

enum class ColourMapName { kTurbo, kViridis };

// The colour map's colour at u in [0, 1] (clamped): entry round(u * 255) of its 256-entry table.
Rgb colour_map_rgb(ColourMapName map, double u);
// Value v on the scale [v_min, v_max] (clamped; v_max <= v_min gives the first colour).
Rgb colour_for_value(ColourMapName map, double v, double v_min, double v_max);

std::string to_hex(Rgb c);  // "#rrggbb"
std::string colour_map_id(ColourMapName map);  // "turbo", "viridis"

}  // namespace mppi::plot
