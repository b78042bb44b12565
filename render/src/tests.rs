use super::*;

fn pixel(png: &[u8], x: u32, y: u32) -> [u8; 4] {
    let img = image::load_from_memory(png).unwrap().to_rgba8();
    img.get_pixel(x, y).0
}

fn square_figure() -> Figure {
    // 10 x 5 m at 10 px/m; a red box in the upper-left quarter of the world (y up).
    let mut fig = Figure::new(
        Aabb {
            min: Vec2::new(0.0, 0.0),
            max: Vec2::new(10.0, 5.0),
        },
        10.0,
    );
    fig.polygon(
        &Polygon::rect(Vec2::new(0.0, 3.0), Vec2::new(2.0, 5.0)),
        &Style::fill(Color::RED),
    );
    fig
}

#[test]
fn png_has_the_size_and_flips_y() {
    let fig = square_figure();
    assert_eq!(fig.size_px(), (100, 50));
    let png = fig.to_png();
    let img = image::load_from_memory(&png).unwrap();
    assert_eq!((img.width(), img.height()), (100, 50));
    // World (1, 4) is near the top-left of the image: red. World (1, 1) is bottom-left: white.
    assert_eq!(pixel(&png, 10, 10), [220, 30, 30, 255]);
    assert_eq!(pixel(&png, 10, 40), [255, 255, 255, 255]);
}

#[test]
fn svg_is_well_formed_and_flips_y() {
    let svg = square_figure().to_svg();
    assert!(svg.starts_with("<svg"));
    assert!(svg.trim_end().ends_with("</svg>"));
    // The rectangle (0,3)-(2,5) maps to pixels x 0..20, y 0..20.
    assert!(
        svg.contains("<polygon points=\"0.00,20.00 20.00,20.00 20.00,0.00 0.00,0.00\""),
        "{svg}"
    );
    assert_eq!(svg.matches("<polygon").count(), 1);
}

#[test]
fn grid_is_embedded_as_png_and_drawn_flipped() {
    let grid = OccupancyGrid::from_ascii(
        "
        ####
        ....
        ????
        ",
        1.0,
    );
    let mut fig = Figure::new(grid.frame.bounds(), 10.0);
    fig.grid(&grid);
    let svg = fig.to_svg();
    assert!(svg.contains("<image") && svg.contains("data:image/png;base64,"));
    let png = fig.to_png();
    assert_eq!(pixel(&png, 5, 5), [0, 0, 0, 255], "top row occupied");
    assert_eq!(pixel(&png, 5, 15), [255, 255, 255, 255], "middle row free");
    assert_eq!(
        pixel(&png, 5, 25),
        [160, 160, 160, 255],
        "bottom row unknown"
    );
}

#[test]
fn huge_bounds_are_clamped() {
    let fig = Figure::new(
        Aabb {
            min: Vec2::new(0.0, 0.0),
            max: Vec2::new(1000.0, 10.0),
        },
        20.0,
    );
    let (w, h) = fig.size_px();
    assert!(w <= MAX_SIDE_PX && h >= 1, "{w}x{h}");
    assert!((fig.px_per_m() - 4.0).abs() < 1e-9);
}

#[test]
fn save_chooses_format_by_extension_and_names_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let fig = square_figure();
    let png = dir.path().join("a.png");
    let svg = dir.path().join("a.svg");
    fig.save(&png).unwrap();
    fig.save(&svg).unwrap();
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));
    assert!(std::fs::read_to_string(&svg).unwrap().starts_with("<svg"));
    let err = fig.save(dir.path().join("a.gif")).unwrap_err();
    assert!(err.to_string().contains("a.gif"), "{err}");
    let err = fig
        .save(dir.path().join("missing").join("a.png"))
        .unwrap_err();
    assert!(err.to_string().contains("missing"), "{err}");
}

#[test]
fn building_figure_colours_rooms_and_marks_the_start() {
    let b = sim_core::generate::generate(&sim_core::generate::GenerateConfig {
        seed: 1,
        area_m2: 800.0,
        ..Default::default()
    });
    let fig = building_figure(&b);
    let svg = fig.to_svg();
    assert!(svg.matches("<polygon").count() > b.rooms.len());
    let png = fig.to_png();
    // A room's interior (away from labels and clutter) shows its colour.
    let room = &b.rooms[0];
    let bb = room.polygon.aabb();
    let p = Vec2::new(bb.min.x + 0.5, bb.min.y + 0.5);
    let (x, y) = fig.px_from_world(p);
    let c = room_color(room.id);
    assert_eq!(pixel(&png, x as u32, y as u32), [c.r, c.g, c.b, 255]);
    // The start is red.
    let (x, y) = fig.px_from_world(b.start.unwrap().position());
    let [r, g, _, _] = pixel(&png, x as u32, y as u32);
    assert!(r > 200 && g < 80);
}

/// Labels in PNGs are real type: anti-aliased (grey levels between ink and paper), as wide as
/// the face's advances say, lower case distinct from upper case, and placed by their anchor.
#[test]
fn png_text_is_antialiased_type_placed_by_its_anchor() {
    let ink_columns = |text: &str, anchor: Anchor| -> (Vec<u32>, bool) {
        let mut fig = Figure::new(
            Aabb {
                min: Vec2::new(0.0, 0.0),
                max: Vec2::new(40.0, 4.0),
            },
            10.0,
        );
        fig.text_anchored(Vec2::new(20.0, 2.0), 16.0, Color::BLACK, text, anchor);
        let img = image::load_from_memory(&fig.to_png()).unwrap().to_rgba8();
        let mut cols = Vec::new();
        let mut grey = false;
        for (x, _, p) in img.enumerate_pixels() {
            if p.0[0] < 250 {
                cols.push(x);
            }
            grey |= (40..200).contains(&p.0[0]);
        }
        cols.sort();
        cols.dedup();
        (cols, grey)
    };
    let (mid, grey) = ink_columns("Exploration time (s)", Anchor::Middle);
    assert!(grey, "anti-aliased edges");
    let (first, last) = (mid[0] as f64, *mid.last().unwrap() as f64);
    let width = super::png::text_width_px("Exploration time (s)", 16.0);
    assert!(
        (last - first - width).abs() < 4.0,
        "{first}..{last} vs {width}"
    );
    assert!(
        ((first + last) / 2.0 - 200.0).abs() < 3.0,
        "centred on x = 200 px"
    );
    let (start, _) = ink_columns("Exploration time (s)", Anchor::Start);
    assert!(
        (start[0] as f64 - 200.0).abs() < 3.0,
        "starts at x = 200 px"
    );
    let (end, _) = ink_columns("Exploration time (s)", Anchor::End);
    assert!(
        (*end.last().unwrap() as f64 - 200.0).abs() < 3.0,
        "ends at x = 200 px"
    );
    assert_ne!(
        ink_columns("abc", Anchor::Start),
        ink_columns("ABC", Anchor::Start)
    );
}
