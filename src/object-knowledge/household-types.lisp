;;;; The household object types of the kitchen (CRAM's household knowledge): the type
;;;; hierarchy, gripping efforts and openings, and the arm configuration for carrying.

(in-package :cram-object-knowledge)

;;; household-item > kitchen-item > cutlery (knife fork spoon), plate, tray, bottle,
;;; cup (mug), milk, cereal (breakfast-cereal), bowl.
(man-int:define-object-type :kitchen-item :household-item)
(man-int:define-object-type :cutlery :kitchen-item)
(man-int:define-object-type :knife :cutlery)
(man-int:define-object-type :fork :cutlery)
(man-int:define-object-type :fork-plastic :cutlery)
(man-int:define-object-type :spoon :cutlery)
(man-int:define-object-type :plate :kitchen-item)
(man-int:define-object-type :tray :kitchen-item)
(man-int:define-object-type :bottle :kitchen-item)
(man-int:define-object-type :cup :kitchen-item)
(man-int:define-object-type :mug :cup)
(man-int:define-object-type :milk :kitchen-item)
(man-int:define-object-type :cereal :kitchen-item)
(man-int:define-object-type :breakfast-cereal :cereal)
(man-int:define-object-type :bowl :kitchen-item)

;;; Efforts: household items 50, milk cartons 20, cereal boxes 45.
;;; Openings (metres): household items 0.10, cutlery 0.05, plates 0.02.
;;; (Container handles are gripped as the environment-manipulation layer declares.)
;;; None of the household types looks the same after any turn about its z axis.
(man-int:define-object-type-gripping :kitchen-item :effort 50 :opening 0.1)
(man-int:define-object-type-gripping :milk :effort 20 :opening 0.1)
(man-int:define-object-type-gripping :cereal :effort 45 :opening 0.1)
(man-int:define-object-type-gripping :cutlery :effort 50 :opening 0.05)
(man-int:define-object-type-gripping :plate :effort 50 :opening 0.02)

;;; Carrying: the bowl always with the arms in :CARRY-TOP (held from above, the gripper
;;; pointing down); cups and cereal boxes after a grasp from the top; everything else in :CARRY.
(man-int:define-object-type-carry-config :bowl :carry-top)
(man-int:define-object-type-carry-config :cup :carry-top :grasps (:top :top2))
(man-int:define-object-type-carry-config :cereal :carry-top :grasps (:top))
