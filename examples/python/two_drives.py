"""Both emulated drives enabled, one homed, both moved together in csp; where they ended."""
import sys

import ecdrive

target = sys.argv[1] if len(sys.argv) > 1 else "sim:mr-j4-tm,bdhde"
with ecdrive.Master(target, cycle_us=1000) as m:
    drives = m.drives
    for ax in drives:
        ax.enable()
    drives[1].home(method=35)  # 35: the current position is the home
    for ax in drives:
        ax.move_by(100000, velocity=500000, acceleration=5000000, wait=False)
    for ax in drives:
        ax.wait()
        print(f"{ax.name}: position {ax.position}, following error {ax.following_error} "
              f"(largest {ax.max_following_error}) counts")
    print(f"largest wake-up latency: {m.max_wake_latency_us:.0f} µs")
