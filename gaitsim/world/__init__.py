"""The simulated world: walking paths, gait plans, C4 foot trajectories and the MuJoCo foot that yields the truth.

Everything here is SI (m, s, rad) and knows neither scenario files nor sensors."""
