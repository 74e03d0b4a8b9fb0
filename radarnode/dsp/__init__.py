"""Pure, vectorised array functions of the radar signal chain.

Axis order everywhere: ``cube[channel, chirp, sample]`` before the FFTs and
``rd[channel, doppler, range]`` after them (Doppler bins fftshifted so that
zero speed is the centre bin).
"""
