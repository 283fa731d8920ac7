"""
Identifying the friction forces
===============================

Table 7's identification: every pair (F1, F2) on the line of Eq. 13 stops the device at the observed
angle alpha_F; along it the stop time t_F grows with the share of F1, and the measured t_F picks the pair.
"""

import quickrelease as qr
from quickrelease.report import plots

ident = qr.identify_friction(alpha0=0.2, alpha_final=0.7378, stop_time=1.05, stored_energy="2.90 kJ")
print(f"F1 = {ident.F1:.2f} N (F1* = {ident.F1_max:.1f} N), F2 = {ident.F2:.2f} N (F2* = {ident.F2_max:.1f} N)")
print(f"feasible stop times: {ident.feasible_stop_times[0]:.4f} to {ident.feasible_stop_times[1]:.4f} s")

fig = plots.identification_figure(ident)
