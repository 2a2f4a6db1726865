use render::math::UVec2;
use render::sampling::Sampler;
fn main() {
    for seed in [0u64, 1, 2, 3, 8, 20, 21, 24, 28] {
        let mut a = Sampler::new(scene::SamplerKind::Independent, 32, seed);
        let mut m = vec![0f64; 40];
        for px in 0..64u32 {
            for idx in 0..32u32 {
                a.start_pixel_sample(UVec2::new(56 + px % 8, 80 + px / 8), idx);
                for d in 0..40 {
                    m[d] += a.next_1d() as f64 - 0.5;
                }
            }
        }
        let z: Vec<String> = m
            .iter()
            .map(|v| format!("{:+.1}", v / (2048f64 / 12.0).sqrt()))
            .collect();
        println!("seed {seed:2}: {}", z.join(" "));
    }
}
