# Targets of the stereo sequence simulator (owned by the simulator work; included from the root).
