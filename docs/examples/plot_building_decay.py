"""
The building's free vibration and its decay
===========================================

After the release the isolated building vibrates freely. Here a 400 t building on isolators of period
2 s with 4 % viscous damping and 12 kN of slider friction, pushed 0.15 m: its exact piecewise
closed-form motion, sampled as a 200 Hz displacement record, and the model-free decay analysis of that
record (turning points, equivalent period, and the combined Coulomb + viscous decrement law).
"""

import matplotlib.pyplot as plt
import numpy as np

from quickrelease import Isolation, free_vibration
from quickrelease.building.decay import analyse_decay

mass = 4.0e5  # kg
iso = Isolation.linear(mass=mass, period=2.0, damping_ratio=0.04, friction=1.2e4)  # kg, s, -, N
motion = free_vibration(iso, d0=0.15)  # pushed 0.15 m, released at rest at t = 0
t = np.arange(-1.0, 14.0, 0.005)
x = motion.state(t)[0]
decay = analyse_decay(t, x, release_time=0.0)
law = decay.law
print(f"stops after {motion.stop_time:.3f} s; T = {decay.natural_period:.5f} s, "
      f"zeta = {law.damping_ratio:.5f}, F_s = {decay.friction_force(mass) / 1e3:.2f} kN")

fig, ax = plt.subplots(figsize=(7, 3.5), layout="constrained")
ax.plot(t, x * 1e3, lw=1, label="displacement x (200 Hz record)")
ax.plot(decay.peak_times, decay.peaks * 1e3, "o", ms=4, label="turning points (located between samples)")
ax.axvline(motion.stop_time, color="0.5", ls=":", label=f"stop, {motion.stop_time:.2f} s")
ax.set_xlabel("time t [s]")
ax.set_ylabel("x [mm]")
ax.set_title("Free vibration of the isolated building after the release")
ax.legend(loc="upper right", fontsize="small")

# %%
# Per half-cycle, the equivalent viscous damping ratio against the amplitude: with slider friction it grows
# as the amplitude falls (constant for purely viscous damping), which is how the record tells them apart.
fig, ax = plt.subplots(figsize=(5, 3.5), layout="constrained")
ax.plot(decay.damping_amplitude * 1e3, decay.equivalent_damping * 100, "o-", ms=4, label="per half-cycle")
ax.axhline(law.damping_ratio * 100, color="0.4", ls="--", label=f"viscous part of the law, {law.damping_ratio:.2%}")
ax.set_xlabel("amplitude [mm]")
ax.set_ylabel("equivalent damping ratio [%]")
ax.legend(fontsize="small")
