"""What the behaviour-tree tests share: a structural check of BehaviorTree.CPP v4 XML
(:mod:`.schema`), synthetic policies (:mod:`.policies`) and the C++ tick program
(``tick.cpp``, built by ``make bt-cpp``)."""
