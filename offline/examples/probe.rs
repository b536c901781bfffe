use prf_offline::world::{World, geometry::Cell};
use prf_shared::robot::RobotModel;
fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().unwrap())
        .collect();
    let q: [f64; 7] = std::array::from_fn(|i| args[i].to_radians());
    let w = World::example();
    let cell = Cell::new(&w, &RobotModel::kmr_iiwa14());
    let r = cell.clearance([w.home.x, w.home.y, 0.0], &q);
    println!("{r:?}");
}
