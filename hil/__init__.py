"""Hardware-in-the-loop device emulators: Modbus devices, the serial weather station, ptys."""
