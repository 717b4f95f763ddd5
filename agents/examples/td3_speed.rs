use hgym_agents::td3::{Td3, Td3Config};
fn main() {
    let (o, a) = (60, 1);
    let mut t = Td3::new("td3", Td3Config::default(), o, a, 0);
    for i in 0..10000 {
        let x: Vec<f64> = (0..o).map(|k| ((i * 7 + k) as f64 * 0.1).sin()).collect();
        t.remember(&x, &[0.1], 0.5, &x, false);
    }
    for _ in 0..20 {
        t.update();
    }
    let n = 300;
    let t0 = std::time::Instant::now();
    for _ in 0..n {
        t.update();
    }
    let dt = t0.elapsed().as_secs_f64();
    println!("{:.1} updates/s ({:.2} ms)", n as f64 / dt, 1e3 * dt / n as f64);
}
