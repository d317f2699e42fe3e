"""fingertip's rows (Zhang et al. 2022, seed 003), registered from the paper's own words.

Registered 2026-12-06 for issue 42. Rows 4-6 are training results the paper measured with its own
protocol (250 Hz, windows of 1,400 points, 40 epochs: `+size=paper`); they are judged only on runs
at that protocol.
"""
from runs.fidelity.registered import register

S = "fingertip"

register(S, "1", "§4.2: textures13, materials10 and combined18 as listed there", "the scene's board lists",
         "every set identical")
register(S, "2", "§2: \"The triboelectric sensor can distinguish materials under a small compression force range. "
         "However, when applying multiple levels of compression force, it's not easy to distinguish materials of "
         "similar electronegativity with only triboelectric sensing data\"",
         "nearest class mean on log f1 per recording of materials10, at each level and pooled",
         "one level >= 2 x chance and >= 1.3 x pooled")   # our thresholds: the paper gives no number
register(S, "3", "Fig. 4: the piezoresistive channel follows the compression force; texture shows in both channels",
         "max X_PR over the level; dominant line at v / period on the twelve ridged boards",
         "force within 5 %; v / period in both channels on >= 10 of 12 boards")
register(S, "4", "§4.4: \"Without the virtual data generation method, the training accuracy is close to 1, when the "
         "validation accuracy is around 10% which is the same as the random probability among 10 materials\"",
         "materials10 without augmentation at the paper's protocol (+size=paper): last-epoch training accuracy, "
         "validation accuracy at the unseen 5 and 20 N", "training accuracy >= 0.95 and unseen-level accuracy <= 20 %")
register(S, "5", "§4.4: \"the average recognition accuracies of the three tasks reach 96.47%, 99.52% and 97.57% ... "
         "The lowest recognition accuracy ... is 90.90% which appears on the classification of silk board\"",
         "unseen-level accuracy with virtual force-level data at the paper's protocol, per task",
         "every task within 10 points of the paper's accuracy")
register(S, "6", "§4.4: \"Our model shows excellent classification ability which has the highest validation accuracy, "
         "smallest model size as well as lowest validation loss among the four models\"; Table 1: val acc 99.06 / "
         "98.14 / 96.30 / 91.79 %, val loss 0.047 / 0.060 / 0.141 / 0.253, size 266,251 / 456,074 / 257,803 / "
         "786,276 (PR-CNN / InceptionTime / Res-CNN / LSTM-FCN)",
         "validation accuracy and loss of the four models at the paper's protocol; size not judged (Table 1 gives "
         "Res-CNN 257,803 below PR-CNN's 266,251)", "PR-CNN's validation accuracy highest and loss lowest of the four")
