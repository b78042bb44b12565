use std::io::Write;
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let out = std::env::args().nth(2).unwrap();
    let b = floorcast_formats::read_floorplan(std::path::Path::new(&path)).unwrap();
    let sim_core::Geometry::Raster { solid } = &b.geometry else {
        panic!()
    };
    let clear = sim_core::distance::distance_to(solid);
    let w = solid.frame.width as i32;
    let h = solid.frame.height as i32;
    let start = b.start.unwrap();
    let sc = solid
        .frame
        .cell_from_world(sim_core::Vec2::new(start.x_m, start.y_m));
    let mut seen = vec![false; (w * h) as usize];
    let mut stack = vec![sc];
    while let Some(c) = stack.pop() {
        if c.x < 0 || c.y < 0 || c.x >= w || c.y >= h {
            continue;
        }
        let i = (c.y * w + c.x) as usize;
        if seen[i] || clear.data[i] < 4.0 {
            continue;
        }
        seen[i] = true;
        for n in c.neighbours4() {
            stack.push(n);
        }
    }
    let mut f = std::fs::File::create(&out).unwrap();
    write!(f, "P5\n{w} {h}\n255\n").unwrap();
    let mut bytes = Vec::new();
    for y in (0..h).rev() {
        for x in 0..w {
            let i = (y * w + x) as usize;
            bytes.push(if solid.data[i] {
                0
            } else if seen[i] {
                255
            } else if clear.data[i] >= 4.0 {
                100
            } else {
                200
            });
        }
    }
    f.write_all(&bytes).unwrap();
}
