//! Lights-per-tile heat map (Harada et al., Figure 5.2b: blue 0, green 25, red 50 and
//! over) and the histogram of tiles by light count (Figure 5.9).

use std::fmt::Write;

/// Colour for a tile holding `count` lights.
pub fn tile_color(count: u32) -> [u8; 3] {
    let t = (count.min(50) as f32) / 25.0;
    let (r, g, b) = if t <= 1.0 {
        (0.0, t, 1.0 - t)
    } else {
        (t - 1.0, 2.0 - t, 0.0)
    };
    [
        (r * 255.0).round() as u8,
        (g * 255.0).round() as u8,
        (b * 255.0).round() as u8,
    ]
}

/// RGB8 pixels of the heat map at output resolution, each pixel coloured by its tile.
pub fn heatmap_rgb8(per_tile: &[u32], tiles_x: u32, tile: u32, width: u32, height: u32) -> Vec<u8> {
    let mut out = Vec::with_capacity((width * height * 3) as usize);
    for y in 0..height {
        for x in 0..width {
            let t = (y / tile) * tiles_x + x / tile;
            out.extend_from_slice(&tile_color(per_tile.get(t as usize).copied().unwrap_or(0)));
        }
    }
    out
}

/// CSV `lights,tiles`: how many tiles hold each light count, from 0 to the maximum.
pub fn histogram_csv(per_tile: &[u32]) -> String {
    let max = per_tile.iter().copied().max().unwrap_or(0) as usize;
    let mut bins = vec![0u32; max + 1];
    for &c in per_tile {
        bins[c as usize] += 1;
    }
    let mut s = String::from("lights,tiles\n");
    for (lights, tiles) in bins.iter().enumerate() {
        let _ = writeln!(s, "{lights},{tiles}");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_scale_matches_the_paper() {
        assert_eq!(tile_color(0), [0, 0, 255]);
        assert_eq!(tile_color(25), [0, 255, 0]);
        assert_eq!(tile_color(50), [255, 0, 0]);
        assert_eq!(tile_color(500), [255, 0, 0]);
    }

    #[test]
    fn histogram_counts_tiles() {
        assert_eq!(
            histogram_csv(&[0, 2, 2, 1]),
            "lights,tiles\n0,1\n1,1\n2,2\n"
        );
    }
}
