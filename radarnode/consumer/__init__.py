"""The consumer side: decoding and assembling radar cycles from CAN traffic."""

from radarnode.consumer.assembler import ClusterCycle, ConsumerStats, CycleAssembler, ObjectCycle

__all__ = ["ClusterCycle", "ConsumerStats", "CycleAssembler", "ObjectCycle"]
