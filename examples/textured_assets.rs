//! Writes the textured scene's assets (`scenes/textured.toml` uses them): two PNG
//! textures drawn here, and a cube as an OBJ with texture coordinates and an MTL naming
//! one of them. The files are committed; run this again only to change them:
//!
//! ```text
//! cargo run --release --example textured_assets -- scenes
//! ```

use std::path::Path;

fn main() -> anyhow::Result<()> {
    let dir = std::env::args().nth(1).unwrap_or_else(|| "scenes".into());
    let dir = Path::new(&dir);
    std::fs::create_dir_all(dir.join("textures"))?;
    checker().save(dir.join("textures/checker.png"))?;
    tiles().save(dir.join("textures/tiles.png"))?;
    std::fs::write(dir.join("textured-cube.obj"), cube_obj())?;
    std::fs::write(
        dir.join("textured-cube.mtl"),
        "# The cube's one material: its diffuse (and so ambient) colour is the tiles texture.\n\
         newmtl tiles\nKa 1 1 1\nKd 1 1 1\nKs 0.3 0.3 0.3\nNs 40\nmap_Kd textures/tiles.png\n",
    )?;
    Ok(())
}

/// 128×128 texels: a 2×2 checker of cream and slate, each square 64 texels wide.
fn checker() -> image::RgbImage {
    image::RgbImage::from_fn(128, 128, |x, y| {
        if (x / 64 + y / 64) % 2 == 0 {
            image::Rgb([236, 226, 204])
        } else {
            image::Rgb([70, 84, 104])
        }
    })
}

/// 128×128 texels: 4×4 tiles, each a colour of its own, with light grout between them and
/// a darker square at the top-left tile to show which way is up.
fn tiles() -> image::RgbImage {
    let palette = [
        [214, 96, 77],
        [240, 180, 80],
        [110, 170, 110],
        [80, 140, 200],
        [150, 110, 190],
    ];
    image::RgbImage::from_fn(128, 128, |x, y| {
        let (tx, ty) = (x / 32, y / 32);
        let (fx, fy) = (x % 32, y % 32);
        if fx < 2 || fy < 2 {
            return image::Rgb([232, 228, 220]);
        }
        if tx == 0 && ty == 0 && (10..22).contains(&fx) && (10..22).contains(&fy) {
            return image::Rgb([40, 40, 48]);
        }
        image::Rgb(palette[((tx + 2 * ty) % 5) as usize])
    })
}

/// A unit cube centred at the origin, each face a quad with texture coordinates from
/// (0, 0) at its bottom-left to (1, 1), seen from outside.
fn cube_obj() -> String {
    let mut s = String::from(
        "# A unit cube, each face textured from (0, 0) to (1, 1); written by\n\
         # examples/textured_assets.rs.\nmtllib textured-cube.mtl\n",
    );
    for (x, y, z) in [
        (-1, -1, -1),
        (1, -1, -1),
        (1, 1, -1),
        (-1, 1, -1),
        (-1, -1, 1),
        (1, -1, 1),
        (1, 1, 1),
        (-1, 1, 1),
    ] {
        s += &format!(
            "v {} {} {}\n",
            x as f32 * 0.5,
            y as f32 * 0.5,
            z as f32 * 0.5
        );
    }
    s += "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl tiles\n";
    // Each face's corners counter-clockwise from outside, from its bottom-left.
    for f in [
        [5, 6, 7, 8], // +z
        [2, 1, 4, 3], // -z
        [6, 2, 3, 7], // +x
        [1, 5, 8, 4], // -x
        [8, 7, 3, 4], // +y
        [1, 2, 6, 5], // -y
    ] {
        s += &format!("f {}/1 {}/2 {}/3 {}/4\n", f[0], f[1], f[2], f[3]);
    }
    s
}
