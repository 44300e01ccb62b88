;;;; Where the household objects are in the IAI kitchen and where they go, per context
;;;; (CRAM's household knowledge): :TABLE-SETTING takes them out of the drawers and the fridge
;;;; onto the dining table, :TABLE-CLEANING puts them into the dishwasher, the trash drawer
;;;; and back into the oven drawer, :TABLE-SETTING-COUNTER takes them from the sink counter
;;;; to the kitchen island.

(in-package :cram-object-knowledge)

(defun kitchen-part (type urdf-name environment &rest more)
  "An object designator for the part URDF-NAME (of type TYPE) of ENVIRONMENT, with MORE
properties ((key value) ...) appended."
  (desig:make-designator :object `((:type ,type) (:urdf-name ,urdf-name) (:part-of ,environment)
                                   ,@more)))

(defun location (&rest properties)
  "A location designator of PROPERTIES ((key value) ...), NIL entries left out."
  (desig:make-designator :location (remove nil properties)))

(defun for-type (type)
  "An object designator of the type the knowledge call asked about (TYPE or its subtype)."
  (desig:make-designator :object `((:type ,(man-int:requested-object-type type)))))

(defun drawer-back (urdf-name environment &rest more)
  "In the drawer URDF-NAME, at its back half (towards the handle)."
  (apply #'location `(:in ,(kitchen-part :drawer urdf-name environment)) '(:side :back) more))

(defun dining-table (environment)
  (kitchen-part :counter-top :dining-area-jokkmokk-table-main environment))

(defun dishwasher-tray (environment)
  "The dishwasher's tray, inside the dishwasher."
  (kitchen-part :drawer :sink-area-dish-washer-tray-bottom environment
                `(:location ,(location `(:in ,(kitchen-part :dishwasher :sink-area-dish-washer-main
                                                            environment))))))

(defun tray-destination (for attachments environment)
  (location `(:above ,(dishwasher-tray environment)) `(:for ,for) `(:attachments ,attachments)))

(defun bowl-reference (environment human context)
  "The bowl where it goes in CONTEXT: spoons and cups go next to it."
  ;; a call of its own: the bowl's location is for a bowl, whatever type asked
  (let ((man-int::*requested-object-type* nil))
    (desig:make-designator :object `((:type :bowl)
                                     (:location ,(man-int:get-object-destination
                                                  :bowl environment human context))))))

;;; ---- likely locations ---------------------------------------------------------------------

(defmethod man-int:get-object-likely-location ((type (eql :bowl)) environment human
                                               (context (eql :table-setting)))
  (drawer-back :sink-area-left-middle-drawer-main environment))

(defmethod man-int:get-object-likely-location ((type (eql :cutlery)) environment human
                                               (context (eql :table-setting)))
  (drawer-back :sink-area-left-upper-drawer-main environment))

(defmethod man-int:get-object-likely-location ((type (eql :cup)) environment human
                                               (context (eql :table-setting)))
  (drawer-back :kitchen-island-left-upper-drawer-main environment))

(defmethod man-int:get-object-likely-location ((type (eql :milk)) environment human
                                               (context (eql :table-setting)))
  (location `(:in ,(kitchen-part :fridge :iai-fridge-door environment '(:level :bottommost)))))

(defmethod man-int:get-object-likely-location ((type (eql :cereal)) environment human
                                               (context (eql :table-setting)))
  "Cereal boxes (breakfast-cereal too) lie on the top board of the oven drawer."
  (location `(:in ,(kitchen-part :drawer :oven-area-area-right-drawer-main environment
                                 '(:level :topmost)))
            '(:side :back) '(:range 0.1) '(:orientation :support-aligned)
            `(:for ,(for-type type))))

(defmethod man-int:get-object-likely-location ((type (eql :household-item)) environment human
                                               (context (eql :table-cleaning)))
  (location `(:on ,(dining-table environment)) '(:side (:front :right))))

(defmethod man-int:get-object-likely-location ((type (eql :household-item)) environment human
                                               (context (eql :table-setting-counter)))
  (location `(:on ,(kitchen-part :counter-top :sink-area-surface environment))
            '(:side (:right :back)) '(:range 0.5)))

;;; ---- destinations ----------------------------------------------------------------------------

(defun table-front (type environment &optional (surface (dining-table environment)))
  "On SURFACE, in its front half, within 0.2 m of its centre: milk and cereal."
  (location `(:on ,surface) `(:for ,(for-type type)) '(:range 0.2) '(:side :front)))

(defmethod man-int:get-object-destination ((type (eql :bowl)) environment human
                                           (context (eql :table-setting)))
  (location `(:on ,(dining-table environment)) `(:for ,(for-type :bowl)) '(:side :front)
            '(:context :table-setting) '(:object-count 2)))

(defmethod man-int:get-object-destination ((type (eql :cutlery)) environment human
                                           (context (eql :table-setting)))
  "Spoons, forks and knives: right of the bowl, close to it, aligned with the table."
  (let ((bowl (bowl-reference environment human context)))
    (location `(:right-of ,bowl) '(:threshold 0.9) `(:near ,bowl) `(:for ,(for-type type))
              '(:orientation :support-aligned))))

(defmethod man-int:get-object-destination ((type (eql :cup)) environment human
                                           (context (eql :table-setting)))
  (let ((bowl (bowl-reference environment human context)))
    (location `(:right-of ,bowl) `(:behind ,bowl) `(:near ,bowl) `(:for ,(for-type :cup)))))

(defmethod man-int:get-object-destination ((type (eql :milk)) environment human
                                           (context (eql :table-setting)))
  (table-front :milk environment))

(defmethod man-int:get-object-destination ((type (eql :cereal)) environment human
                                           (context (eql :table-setting)))
  (table-front type environment))

(defmethod man-int:get-object-destination ((type (eql :bottle)) environment human
                                           (context (eql :table-setting)))
  (table-front type environment))

;;; Setting a table on the kitchen island from the sink counter.
(defmethod man-int:get-object-destination ((type (eql :household-item)) environment human
                                           (context (eql :table-setting-counter)))
  (let ((bowl (bowl-reference environment human context)))
    (location `(:right-of ,bowl) `(:near ,bowl) `(:for ,(for-type type)))))

(defmethod man-int:get-object-destination ((type (eql :bowl)) environment human
                                           (context (eql :table-setting-counter)))
  (location `(:on ,(kitchen-part :counter-top :kitchen-island-surface environment))
            `(:for ,(for-type :bowl)) '(:context :table-setting) '(:object-count 2)))

;;; Cleaning: bowl, cup and spoon into the dishwasher tray's slots, milk and bottles into the
;;; trash drawer, cereal back where it came from, the rest into the sink.
(defmethod man-int:get-object-destination ((type (eql :bowl)) environment human
                                           (context (eql :table-cleaning)))
  (tray-destination (desig:make-designator :object '((:type :bowl) (:name :some-name)))
                    '(:dish-washer-drawer-right) environment))

(defmethod man-int:get-object-destination ((type (eql :spoon)) environment human
                                           (context (eql :table-cleaning)))
  (tray-destination (for-type :spoon) '(:dish-washer-drawer-center) environment))

(defmethod man-int:get-object-destination ((type (eql :cup)) environment human
                                           (context (eql :table-cleaning)))
  (tray-destination (for-type :cup) '(:dish-washer-drawer-left-flipped-around-x
                                      :dish-washer-drawer-left-flipped-around-y)
                    environment))

(defun trash-drawer-destination (type environment)
  (location `(:above ,(kitchen-part :drawer :sink-area-trash-drawer-main environment))
            '(:z-offset -0.05) '(:side (:back :left)) '(:range 0.2) `(:for ,(for-type type))))

(defmethod man-int:get-object-destination ((type (eql :milk)) environment human
                                           (context (eql :table-cleaning)))
  (trash-drawer-destination type environment))

(defmethod man-int:get-object-destination ((type (eql :bottle)) environment human
                                           (context (eql :table-cleaning)))
  (trash-drawer-destination type environment))

(defmethod man-int:get-object-destination ((type (eql :cereal)) environment human
                                           (context (eql :table-cleaning)))
  "Cereal boxes go back where they came from."
  (man-int:get-object-likely-location (man-int:requested-object-type type) environment human
                                      :table-setting))

(defmethod man-int:get-object-destination ((type (eql :kitchen-item)) environment human
                                           (context (eql :table-cleaning)))
  (location `(:above ,(kitchen-part :sink :sink-area-sink environment))
            '(:side :left) '(:z-offset -0.1)))

(defmethod man-int:get-object-destination ((type (eql :mug)) environment human
                                           (context (eql :table-cleaning)))
  (man-int:get-object-destination :kitchen-item environment human context))

;;; ---- the location type of an object ---------------------------------------------------------

(defun man-int:get-object-location-type (object)
  "The type (a keyword) of the object the object designator OBJECT lies in, on or above, by
its LOCATION's IN, ON or ABOVE reference (e.g. :DRAWER), or by that of the designator it was
first described by (before perception); NIL when neither says."
  (unless (typep object 'desig:object-designator)
    (error 'man-int:manipulation-knowledge-error
           :format-control "GET-OBJECT-LOCATION-TYPE: expected an object designator, got ~s."
           :format-arguments (list object)))
  (let ((location (or (desig:desig-prop-value object :location)
                      (desig:desig-prop-value (desig:first-desig object) :location))))
    (when (typep location 'desig:location-designator)
      (let ((reference (some (lambda (key) (desig:desig-prop-value location key)) '(:in :on :above))))
        (when (typep reference 'desig:object-designator)
          (let ((type (desig:desig-prop-value reference :type)))
            (and (symbolp type) type (intern (symbol-name type) :keyword))))))))
