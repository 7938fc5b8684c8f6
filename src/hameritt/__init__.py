"""hameritt for Python clients: hameritt.msg and hameritt.srv (generated), hameritt.lockstep."""
