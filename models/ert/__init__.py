"""ERT image reconstructions, one module each as pyEIT splits them: `tikhonov` (calibrated
Tikhonov with deconvolution and a coefficient field), `gauss_newton` (one-step, with a choice of
`priors`), `greit`, `learned_inverse` (a regressor on GREIT's image) and
`learned_readings_inverse` (an MLP on the patch loads). What they share: `reconstruction` (the
estimator contract, `for_sensor`), `validation` (the one check of their inputs), `linear_image`
(the estimator of a linear map to an image, then the read-out), `pixel_grid`, `image_readout`
(sub-pixel position); `registry` names them for the studies and benches.

The measurement model they invert (protocol, forward solve, readings, the Jacobian) is the data
floor's data/ert/: the scene simulates with it, and the floors let models/ import data/, never
the other way round."""
