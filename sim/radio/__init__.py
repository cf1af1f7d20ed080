"""Vehicle-to-vehicle radio: what a vehicle broadcasts about itself, signed, and the channel it crosses.

- :mod:`.message`: the message (who sent it, its sequence number, when, where the sender is, how fast,
  its brake) and its bytes, signed with Ed25519 (libsodium through PyNaCl), as IEEE 1609.2 and ETSI
  ITS sign a vehicle's cooperative awareness messages;
- :mod:`.keys`: the fleet's keys (drawn for each episode by the world, or a real fleet's files) and the
  car's trust store of public keys;
- :mod:`.channel`: the simulated radio, with its rate, latency, loss and range.

A world manager's vehicle says what it would broadcast (``WorldManager.broadcasts``); the env's radio
signs it with the vehicle's key and delivers it to the car as the ``radio`` observation, like any
sensor's reading. Nothing here knows MuJoCo.
"""

from racf.sim.radio.channel import RADIO_SLOTS, Radio, RadioConfig
from racf.sim.radio.keys import FLEET, FleetKeys, load_trust_store, write_fleet_keys
from racf.sim.radio.message import MESSAGE_BYTES, SIGNED_BYTES, Broadcast, V2VMessage, open_signed, sign

__all__ = ["Broadcast", "V2VMessage", "MESSAGE_BYTES", "SIGNED_BYTES", "sign", "open_signed", "FleetKeys",
           "load_trust_store", "write_fleet_keys", "FLEET", "Radio", "RadioConfig", "RADIO_SLOTS"]
