//! An argmin observer for the layout examples: prints the iteration, the objective and the
//! parameters as the example words them, after every iteration.

use argmin::core::observers::Observe;
use argmin::core::{Error, KV, State};
use nalgebra::DVector;

/// Prints `iteration  objective  words(parameters)` after every iteration.
pub struct PrintObjective(pub fn(&[f64]) -> String);

impl<I: State<Param = DVector<f64>, Float = f64>> Observe<I> for PrintObjective {
    fn observe_iter(&mut self, state: &I, _kv: &KV) -> Result<(), Error> {
        let words = state
            .get_param()
            .map_or_else(String::new, |p| (self.0)(p.as_slice()));
        let line = format!(
            "{:>4}  {:>12.5e}  {words}",
            state.get_iter(),
            state.get_cost()
        );
        println!("{}", line.trim_end());
        Ok(())
    }
}
