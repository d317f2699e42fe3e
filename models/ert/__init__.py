"""ERT image reconstructions (one idea per file, as pyEIT splits them): `readings` (the channels
through the transfer matrix, the pixel Jacobian), `priors`, `image_readout` (sub-pixel position),
`linear_image` (the shared estimator: a linear map to an image, then the read-out),
`gauss_newton` and `greit`."""
