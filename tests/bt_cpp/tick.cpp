// ehatp-bt-tick: load a tree written by `ehatp export bt --format btcpp4` in BehaviorTree.CPP 4,
// tick it to its end with a scripted human, and print what happened, one line per event.
//
//   ehatp-bt-tick TREE.xml [--choices 0,1,...]   tick the tree (exit 0: SUCCESS, 1: FAILURE)
//   ehatp-bt-tick --model                       the TreeNodesModel of the nodes registered here
//   ehatp-bt-tick --xsd                         BehaviorTree.CPP's schema for them
//
// The custom nodes are registered as docs/behaviour-trees.md tells a robot program to: every
// port a std::string, the optional ones with a default. The human's k-th turn takes the
// action expected[c % size] where c is the k-th of --choices (cycling; default 0), or, for
// c = -1, "dance", an action no policy covers. Lines (fields separated by tabs):
//   loaded  <nodes instantiated>
//   robot   <kind> <action> <completes> <answer>   kind: action, wait, silence, say
//   human   <policy node> <action>
//   uncovered <observed> <expected>
//   goal    <policy node>
//   status  SUCCESS | FAILURE  <ticks>
#include <behaviortree_cpp/bt_factory.h>
#include <behaviortree_cpp/xml_parsing.h>

#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace
{
std::vector<int> g_choices{ 0 };
size_t g_turn = 0;

std::vector<std::string> split(const std::string& text)
{
  std::vector<std::string> out;
  std::stringstream in(text);
  std::string item;
  while(std::getline(in, item, ';'))
  {
    if(!item.empty())
    {
      out.push_back(item);
    }
  }
  return out;
}

std::string no_spaces(const std::string& text)
{
  std::string out;
  for(char c : text)
  {
    if(c != ' ' && c != '\t' && c != '\n' && c != '\r')
    {
      out += c;
    }
  }
  return out;
}

std::string join(const std::vector<std::string>& items, const std::string& sep)
{
  std::string out;
  for(size_t i = 0; i < items.size(); ++i)
  {
    out += (i != 0 ? sep : "") + items[i];
  }
  return out;
}

// the value of an input port, its default when the XML leaves it out
std::string port(const BT::TreeNode& node, const std::string& name)
{
  auto value = node.getInput<std::string>(name);
  if(!value)
  {
    throw BT::RuntimeError("port ", name, " of ", node.registrationName(), ": ",
                           value.error());
  }
  return value.value();
}

std::pair<std::string, BT::PortInfo> completes_port()
{
  return BT::InputPort<std::string>("completes", std::string(),
                                    "the label of the policy's robot move this node finishes");
}

void robot(const std::string& kind, const std::string& action, const BT::TreeNode& node,
           const std::string& answer = "")
{
  std::cout << "robot\t" << kind << "\t" << action << "\t" << port(node, "completes") << "\t"
            << answer << "\n";
}

class RobotAction : public BT::SyncActionNode
{
public:
  RobotAction(const std::string& name, const BT::NodeConfig& config)
    : BT::SyncActionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<std::string>("action", "the action as the policy prints it"),
             BT::InputPort<std::string>("action_name", "the action's name"),
             BT::InputPort<std::string>("args", std::string(), "its arguments, separated by ';'"),
             completes_port() };
  }
  BT::NodeStatus tick() override
  {
    robot("action", port(*this, "action"), *this);
    return BT::NodeStatus::SUCCESS;
  }
};

class RobotWait : public BT::SyncActionNode
{
public:
  RobotWait(const std::string& name, const BT::NodeConfig& config)
    : BT::SyncActionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { completes_port() };
  }
  BT::NodeStatus tick() override
  {
    robot("wait", "wait", *this);
    return BT::NodeStatus::SUCCESS;
  }
};

class Silence : public BT::SyncActionNode
{
public:
  Silence(const std::string& name, const BT::NodeConfig& config)
    : BT::SyncActionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { completes_port() };
  }
  BT::NodeStatus tick() override
  {
    robot("silence", "silence", *this);
    return BT::NodeStatus::SUCCESS;
  }
};

class Say : public BT::SyncActionNode
{
public:
  Say(const std::string& name, const BT::NodeConfig& config) : BT::SyncActionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<std::string>("kind", "inform, answer, ask or announce"),
             BT::InputPort<std::string>("literals", std::string(), "inform: the literals told"),
             BT::InputPort<std::string>("question", std::string(), "answer, ask: the question"),
             BT::InputPort<std::string>("answer", std::string(), "answer: yes, no or empty"),
             BT::InputPort<std::string>("intention", std::string(), "announce: the robot's tasks"),
             completes_port() };
  }
  BT::NodeStatus tick() override
  {
    const std::string kind = port(*this, "kind");
    if(kind == "inform")
    {
      robot("say", "inform(" + join(split(port(*this, "literals")), ", ") + ")", *this);
    }
    else if(kind == "answer")
    {
      robot("say", "answer(" + port(*this, "question") + ")", *this, port(*this, "answer"));
    }
    else if(kind == "ask")
    {
      robot("say", "ask(" + port(*this, "question") + ")", *this);
    }
    else if(kind == "announce")
    {
      robot("say", "announce(" + port(*this, "intention") + ")", *this);
    }
    else
    {
      return BT::NodeStatus::FAILURE;
    }
    return BT::NodeStatus::SUCCESS;
  }
};

// RUNNING on its first tick (the human has not acted yet), then the scripted choice
class WaitHumanAction : public BT::StatefulActionNode
{
public:
  WaitHumanAction(const std::string& name, const BT::NodeConfig& config)
    : BT::StatefulActionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { BT::OutputPort<std::string>("action", "the human's action"),
             BT::InputPort<std::string>("expected", "the actions the policy covers") };
  }
  BT::NodeStatus onStart() override
  {
    return BT::NodeStatus::RUNNING;
  }
  BT::NodeStatus onRunning() override
  {
    const auto expected = split(port(*this, "expected"));
    const int c = g_choices[g_turn++ % g_choices.size()];
    const std::string chosen =
        (c < 0 || expected.empty()) ? "dance" : expected[size_t(c) % expected.size()];
    std::string key = config().output_ports.at("action");  // {human_action_N}
    std::string node = key.substr(key.rfind('_') + 1);
    node = node.substr(0, node.size() - 1);
    std::cout << "human\t" << node << "\t" << chosen << "\n";
    setOutput("action", chosen);
    return BT::NodeStatus::SUCCESS;
  }
  void onHalted() override
  {}
};

class HumanDid : public BT::ConditionNode
{
public:
  HumanDid(const std::string& name, const BT::NodeConfig& config)
    : BT::ConditionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<std::string>("observed", "the action observed"),
             BT::InputPort<std::string>("action", "the action of this branch") };
  }
  BT::NodeStatus tick() override
  {
    return no_spaces(port(*this, "observed")) == no_spaces(port(*this, "action")) ?
               BT::NodeStatus::SUCCESS :
               BT::NodeStatus::FAILURE;
  }
};

class ReportUncovered : public BT::SyncActionNode
{
public:
  ReportUncovered(const std::string& name, const BT::NodeConfig& config)
    : BT::SyncActionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<std::string>("observed", "the action observed"),
             BT::InputPort<std::string>("expected", "the actions the policy covers") };
  }
  BT::NodeStatus tick() override
  {
    const std::string seen = port(*this, "observed");
    bool covered = false;
    for(const auto& e : split(port(*this, "expected")))
    {
      covered = covered || no_spaces(e) == no_spaces(seen);
    }
    if(!covered)
    {
      std::cout << "uncovered\t" << seen << "\t" << port(*this, "expected") << "\n";
    }
    return BT::NodeStatus::SUCCESS;
  }
};

class GoalReached : public BT::SyncActionNode
{
public:
  GoalReached(const std::string& name, const BT::NodeConfig& config)
    : BT::SyncActionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<std::string>("node", "the policy node reached") };
  }
  BT::NodeStatus tick() override
  {
    std::cout << "goal\t" << port(*this, "node") << "\n";
    return BT::NodeStatus::SUCCESS;
  }
};
}  // namespace

int main(int argc, char** argv)
{
  BT::BehaviorTreeFactory factory;
  factory.registerNodeType<RobotAction>("RobotAction");
  factory.registerNodeType<RobotWait>("RobotWait");
  factory.registerNodeType<Say>("Say");
  factory.registerNodeType<Silence>("Silence");
  factory.registerNodeType<WaitHumanAction>("WaitHumanAction");
  // joint steps: the human's action seen as it starts; the same scripted choice
  factory.registerNodeType<WaitHumanAction>("WaitHumanStart");
  factory.registerNodeType<HumanDid>("HumanDid");
  factory.registerNodeType<ReportUncovered>("ReportUncovered");
  factory.registerNodeType<GoalReached>("GoalReached");

  std::string file;
  for(int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    if(arg == "--model")
    {
      std::cout << BT::writeTreeNodesModelXML(factory) << "\n";
      return 0;
    }
    if(arg == "--xsd")
    {
      std::cout << BT::writeTreeXSD(factory) << "\n";
      return 0;
    }
    if(arg == "--choices" && i + 1 < argc)
    {
      g_choices.clear();
      std::stringstream in(argv[++i]);
      std::string item;
      while(std::getline(in, item, ','))
      {
        g_choices.push_back(std::stoi(item));
      }
      if(g_choices.empty())
      {
        g_choices.push_back(0);
      }
      continue;
    }
    file = arg;
  }
  if(file.empty())
  {
    std::cerr << "usage: ehatp-bt-tick TREE.xml [--choices 0,1,...] | --model | --xsd\n";
    return 2;
  }
  try
  {
    auto tree = factory.createTreeFromFile(file);
    size_t nodes = 0;
    tree.applyVisitor([&nodes](const BT::TreeNode*) { ++nodes; });
    std::cout << "loaded\t" << nodes << "\n";
    BT::NodeStatus status = BT::NodeStatus::RUNNING;
    long ticks = 0;
    while(status == BT::NodeStatus::RUNNING && ticks < 10000000)
    {
      status = tree.tickOnce();
      ++ticks;
    }
    std::cout << "status\t" << BT::toStr(status) << "\t" << ticks << std::endl;
    return status == BT::NodeStatus::SUCCESS ? 0 : 1;
  }
  catch(const std::exception& e)
  {
    std::cout << std::flush;
    std::cerr << file << ": " << e.what() << "\n";
    return 2;
  }
}
