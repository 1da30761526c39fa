"""What every command runs on: files written atomically with the user's umask, progress
displays, Ctrl-C handling, the work clocks budgets count, and numba's compiling and its notices."""
