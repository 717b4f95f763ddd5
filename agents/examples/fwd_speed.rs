use hgym_agents::nn::{Activation, Init, Mlp, Tape};
use hgym_agents::rng::Rng;
fn main() {
    let mut rng = Rng::seed(0);
    let net: Mlp<f32> = Mlp::new(
        &[60, 256, 256, 1],
        Activation::Relu,
        Activation::Tanh,
        Init::FanIn,
        Init::FanIn,
        &mut rng,
    );
    let x: Vec<f32> = (0..60).map(|i| (i as f32).sin()).collect();
    let mut tape = Tape::new();
    let mut s = 0.0;
    let t = std::time::Instant::now();
    for _ in 0..20000 {
        s += net.forward(&x, 1, &mut tape)[0];
    }
    println!("{:.2} us {s}", t.elapsed().as_secs_f64() * 1e6 / 20000.0);
}
