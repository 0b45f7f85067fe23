//! profiling helper (not committed)
use rl_core::model::DerivativeData;
use rl_core::{Data, algo, loader};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let opts = loader::UrdfOptions {
        floating_base: true,
        ..Default::default()
    };
    let m = loader::load_file_with::<64>(std::path::Path::new(&args[1]), &opts)
        .unwrap()
        .model;
    let which = args[2].as_str();
    let iters: usize = args.get(3).map(|x| x.parse().unwrap()).unwrap_or(2000);
    let mut d = Box::new(Data::<64>::new());
    let mut dd = Box::new(DerivativeData::<64>::new());
    let mut q = vec![0.0; m.nq()];
    let mut s = 1u64;
    m.random_configuration(&mut q, || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    });
    let v = vec![0.3; m.dof()];
    let a = vec![0.2; m.dof()];
    let tau = algo::rnea(&m, &mut d, &q, &v, &a).unwrap().to_vec();
    let mut acc = 0.0;
    let t = std::time::Instant::now();
    for _ in 0..iters {
        match which {
            "drnea" => {
                acc += algo::rnea_derivatives(&m, &mut d, &mut dd, &q, &v, &a)
                    .unwrap()
                    .dtau_dq
                    .get(0, 0)
            }
            "rnea" => acc += algo::rnea(&m, &mut d, &q, &v, &a).unwrap()[0],
            "aba" => acc += algo::aba(&m, &mut d, &q, &v, &tau).unwrap()[0],
            _ => {
                acc += algo::aba_derivatives(&m, &mut d, &mut dd, &q, &v, &tau)
                    .unwrap()
                    .ddq_dq
                    .get(0, 0)
            }
        }
    }
    println!(
        "{which}: {:.1} ns per call ({acc})",
        t.elapsed().as_secs_f64() * 1e9 / iters as f64
    );
}
