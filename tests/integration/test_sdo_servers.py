"""Additional SDO servers over vcan (issue 15 part 3): a device from an EDS with 0x1201/0x1202 serves a second and a
third SDO channel beside the default one; python-canopen's clients on those COB-IDs read and write through them, a
channel configured by SDO starts answering once both its COB-IDs are valid, and CiA 301's COB-ID rules hold."""
import struct
from pathlib import Path

import pytest
from canopen.sdo.exceptions import SdoAbortedError, SdoCommunicationError

from conftest import remote

EDS = Path(__file__).resolve().parents[2] / "tests" / "eds" / "files" / "sdo-servers.eds"


def channel(network, node, rx_cobid, tx_cobid, timeout):
    """A python-canopen client on another SDO server of the node (canopen 2.4's add_sdo on a node already in a
    network subscribes the client but does not give it the network to send on)."""
    client = node.add_sdo(rx_cobid, tx_cobid)
    client.network = network
    client.RESPONSE_TIMEOUT = timeout
    return client


def test_every_server_of_the_dictionary_answers_on_its_own_cob_ids(emulator, network, capture):
    node_id = 0x22
    emulator(f"{EDS}:{node_id}")
    capture.wait_for(0x700 + node_id, data=b"\x00", timeout=3)
    node = remote(network, "buerkert", node_id, od=str(EDS))
    third = channel(network, node, 0x680 + node_id, 0x6A0 + node_id, 5.0)  # 0x1202: $NODEID+0x680 / +0x6A0
    assert third.upload(0x1018, 1) == struct.pack("<I", 0xABC)
    third.download(0x1017, 0, struct.pack("<H", 250))
    assert node.sdo.upload(0x1017, 0) == struct.pack("<H", 250)  # one dictionary behind all servers
    assert capture.wait_for(0x6A0 + node_id, count=2, timeout=2)

    # 0x1201 starts invalid: configured through the default server, then used.
    second = channel(network, node, 0x6C0, 0x6D0, 1.0)
    node.sdo.download(0x1201, 2, struct.pack("<I", 0x6D0))
    node.sdo.download(0x1201, 1, struct.pack("<I", 0x6C0))
    assert second.upload(0x1000, 0) == node.sdo.upload(0x1000, 0)
    with pytest.raises(SdoAbortedError) as refused:  # a valid COB-ID changes only through "not valid"
        node.sdo.download(0x1201, 1, struct.pack("<I", 0x6C1))
    assert refused.value.code == 0x06090030
    node.sdo.download(0x1201, 1, struct.pack("<I", 0x800006C0))
    with pytest.raises(SdoCommunicationError):  # nobody answers on a server that is not valid
        second.upload(0x1000, 0)
