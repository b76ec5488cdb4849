//! `tdcr check` and `tdcr example`.

use crate::failure::{Failure, emit};
use crate::robot_args::read_robot;
use tdcr::Method;

/// `tdcr check FILE`: reads and checks a robot file (with its fixed mesh, if any, against the
/// resolution rule), one line on success.
pub fn run(file: &str) -> Result<(), Failure> {
    let (name, parsed) = read_robot(file)?;
    let r = &parsed.robot;
    // The file's fixed mesh must resolve the robot, as `solve` would require.
    if parsed.solver.method == Method::Collocation {
        tdcr::collocation::check_resolution(r, &parsed.solver.collocation)
            .map_err(|e| Failure::Input(format!("{name}: {e}")))?;
    }
    let pulled = r.tendons.iter().filter(|t| t.tension > 0.0).count();
    emit(&format!(
        "{name}: OK: a {:.4} m rod with {} tendon(s) ({pulled} pulled), {} point load(s); solver: {}\n",
        r.length(),
        r.tendons.len(),
        r.loads.point.len(),
        parsed.solver.method
    ))
}

/// `tdcr example`: the prototype as a commented robot file.
pub fn example() -> Result<(), Failure> {
    emit(&tdcr::io::example())
}
