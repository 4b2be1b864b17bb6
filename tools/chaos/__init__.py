"""`chronav chaos`: the whole system under a fault schedule (schedule, injector, what survived)."""
