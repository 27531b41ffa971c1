"""Team simulator: scenarios, trajectories, sensors, simulate(scenario, rng) -> Recording."""
