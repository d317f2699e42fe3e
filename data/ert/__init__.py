"""The ERT textile skin's measurement model, one idea per module as pyEIT splits it: `protocol`
(injection and measurement patterns, channel names), `cells` (the square cells, fabric patches or
image pixels, over the sheet's grid nodes), `forward` (the sensor's sheet solver), `readings`
(channels from the transfer-resistance matrix Z), `jacobian` (the one adjoint sensitivity of Z and
its channel views) and `patch_loads` (where a press loads the patches).

It sits on the data floor because the scene (data/scenes/ert.py) simulates with it; the
reconstructions that invert it are one floor up, in models/ert/."""
